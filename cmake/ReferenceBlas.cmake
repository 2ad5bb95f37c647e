# Reference BLAS / LAPACK for every program we link, so that results do not depend on memory
# layout. OpenCV's calibrateCamera (the intrinsics stage) calls BLAS / LAPACK through whatever
# libblas.so.3 / liblapack.so.3 the system's alternatives select; on Debian 12 that is ATLAS
# as soon as libceres3 pulls libatlas3-base in, and ATLAS's kernels give last-bit differences
# that depend on buffer addresses, which the identification then amplifies: study trials did
# not reproduce bit for bit (tests/calib/vision/heap_layout_reproducibility_test.cc has the
# measurement). So every program names libblas.so.3 and liblapack.so.3 among its own
# dependencies (--no-as-needed) and carries a DT_RPATH to Netlib's reference build (packages
# libblas3, liblapack3): the loader maps a program's own dependencies before theirs, so the
# reference libraries are in place before OpenCV or CHOLMOD asks for the same soname (CHOLMOD
# has DT_RUNPATH $ORIGIN, which would ignore the program's path), whatever the system's
# alternatives say. Nothing else in the process uses BLAS for large problems (Ceres runs
# DENSE_QR on Eigen), so the reference build costs nothing measurable; it was faster here on
# the intrinsics problem (1.5 s against 2.1 s for 25 calibrations).
function(twinbench_use_reference_blas)
  set(_dirs)
  foreach(_lib blas lapack)
    set(_dir /usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}/${_lib})
    if(NOT EXISTS ${_dir}/lib${_lib}.so.3)
      message(WARNING "reference ${_lib} not found at ${_dir}/lib${_lib}.so.3 (Debian package "
                      "lib${_lib}3): results may depend on memory layout with ATLAS or OpenBLAS, "
                      "and study trials may not reproduce bit for bit")
      return()
    endif()
    list(APPEND _dirs ${_dir})
  endforeach()
  list(JOIN _dirs ":" _path)
  list(GET _dirs 0 _blas_dir)
  list(GET _dirs 1 _lapack_dir)
  add_link_options(LINKER:--disable-new-dtags LINKER:-rpath,${_path}
                   LINKER:--push-state,--no-as-needed ${_blas_dir}/libblas.so.3
                   ${_lapack_dir}/liblapack.so.3 LINKER:--pop-state)
  message(STATUS "Reference BLAS / LAPACK by DT_RPATH: ${_path}")
endfunction()
