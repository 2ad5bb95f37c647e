# Architecture rule of DESIGN.md: calib/ (the estimator) never includes MuJoCo or sim/.
function(twinbench_check_calib_isolation dir)
  file(GLOB_RECURSE _sources ${dir}/*.h ${dir}/*.cc ${dir}/*.cpp ${dir}/*.hpp)
  foreach(_f IN LISTS _sources)
    file(STRINGS ${_f} _hits REGEX "#[ \t]*include[ \t]*[<\"](mujoco/|mujoco\\.h|sim/)")
    if(_hits)
      message(FATAL_ERROR "${_f} includes MuJoCo or sim/ (${_hits}): calib/ must build "
                          "without the twin (see DESIGN.md)")
    endif()
  endforeach()
endfunction()

# Fails the configure step if a target links MuJoCo, directly or through its link interface.
function(twinbench_assert_no_mujoco target)
  get_target_property(_libs ${target} LINK_LIBRARIES)
  get_target_property(_ilibs ${target} INTERFACE_LINK_LIBRARIES)
  foreach(_l IN LISTS _libs _ilibs)
    if(_l MATCHES "mujoco" OR _l MATCHES "sim")
      message(FATAL_ERROR "target ${target} links ${_l}: calib/ must not depend on MuJoCo or sim/")
    endif()
  endforeach()
endfunction()

# Puts a poisoned mujoco/mujoco.h first on the target's include path, so that any include of
# MuJoCo from the target's sources stops compilation with a message, whatever the grep missed.
function(twinbench_poison_mujoco_include target)
  set(_dir ${CMAKE_BINARY_DIR}/poison_include)
  file(WRITE ${_dir}/mujoco/mujoco.h
       "#error \"calib/ must not include MuJoCo: the estimator never sees the twin (DESIGN.md)\"\n")
  target_include_directories(${target} BEFORE PRIVATE ${_dir})
endfunction()
