# Install rules, the exported CMake package and the Debian package (CPack), included by the
# top-level CMakeLists.txt after its subdirectories. Layout under the prefix (/usr in the .deb):
#   bin/twinbench
#   share/twinbench/{models,scenarios}      read by twinbench (bench/io/data_dir.h)
#   share/twinbench/schemas/                the scenario format as a JSON Schema
#   include/twinbench/calib/...             the estimator's headers
#   lib/<arch>/libtwinbench_calib.a         twinbench::calib
#   lib/<arch>/cmake/twinbench/             twinbenchConfig.cmake and friends
include(CMakePackageConfigHelpers)

set(TWINBENCH_INSTALL_DATADIR ${CMAKE_INSTALL_DATADIR}/${TWINBENCH_DATA_SUBDIR})
set(TWINBENCH_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/twinbench)

# The data the binary reads: the shipped models (YAML, URDF) and scenarios, whose model paths
# are relative to the scenario file (../models/...), so both keep their places.
# The scenario format as a JSON Schema (`twinbench schema` writes it; the test
# schema_up_to_date keeps the file current), for editors and tools: share/twinbench/schemas/.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/models ${PROJECT_SOURCE_DIR}/scenarios
                  ${PROJECT_SOURCE_DIR}/schemas
        DESTINATION ${TWINBENCH_INSTALL_DATADIR} COMPONENT twinbench)
foreach(_doc LICENSE CITATION.cff)
  if(EXISTS ${PROJECT_SOURCE_DIR}/${_doc})
    install(FILES ${PROJECT_SOURCE_DIR}/${_doc}
            DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT twinbench)
  endif()
endforeach()

# The estimator's package. Architecture rule: its link interface is Eigen, Ceres and OpenCV;
# refuse to configure if anything of the twin (sim, MuJoCo, OSMesa) reached it.
get_target_property(_calib_interface calib INTERFACE_LINK_LIBRARIES)
foreach(_l IN LISTS _calib_interface)
  if(_l MATCHES "mujoco|^sim$|OSMESA|bench")
    message(FATAL_ERROR "twinbench::calib would export ${_l}: calib/ must not depend on the twin")
  endif()
endforeach()
install(EXPORT twinbenchTargets NAMESPACE twinbench:: FILE twinbenchTargets.cmake
        DESTINATION ${TWINBENCH_INSTALL_CMAKEDIR} COMPONENT calib)
set(TWINBENCH_EIGEN_MIN 3.3)
set(TWINBENCH_OPENCV_COMPONENTS "core imgproc imgcodecs calib3d")
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/twinbenchConfig.cmake.in
  ${PROJECT_BINARY_DIR}/cmake/twinbenchConfig.cmake
  INSTALL_DESTINATION ${TWINBENCH_INSTALL_CMAKEDIR}
  PATH_VARS TWINBENCH_INSTALL_INCLUDEDIR TWINBENCH_INSTALL_DATADIR)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/cmake/twinbenchConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/cmake/twinbenchConfig.cmake
              ${PROJECT_BINARY_DIR}/cmake/twinbenchConfigVersion.cmake
        DESTINATION ${TWINBENCH_INSTALL_CMAKEDIR} COMPONENT calib)

# The Debian package (cpack -G DEB in the build tree): one package with the tool, its data and
# the estimator's development files. Runtime dependencies from dpkg-shlibdeps (package
# dpkg-dev); building against twinbench::calib needs the -dev packages it recommends.
set(TWINBENCH_DEB_MAINTAINER "twinbench maintainers <maintainers@twinbench.invalid>"
    CACHE STRING "Maintainer field of the Debian package (Name <email>)")
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME twinbench)
set(CPACK_PACKAGE_VENDOR "The twinbench authors")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT "${TWINBENCH_DEB_MAINTAINER}")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_DESCRIPTION
    "twinbench simulates a cell of two robot arms, a hand camera, a calibration board or a laser "
    "tracker in MuJoCo, runs kinematic calibration procedures on it and scores the identified "
    "models against the twin's truth. Includes the shipped robot models and scenarios, and the "
    "estimator library twinbench::calib (static, with its CMake package) for hardware drivers.")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_DEBIAN_PACKAGE_RELEASE 1)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# libegl1: the GPU render path, opened with dlopen (sim/render/gl_context.h), so shlibdeps cannot
# see it; without it twinbench renders with OSMesa.
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "libeigen3-dev, libceres-dev, libopencv-dev, libegl1")
set(CPACK_DEBIAN_COMPRESSION_TYPE gzip)
set(CPACK_STRIP_FILES bin/twinbench)
set(CPACK_SOURCE_IGNORE_FILES "/build.*/" "/\\\\.git/")
include(CPack)
