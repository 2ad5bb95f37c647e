# Script mode (cmake -DDIR=... -P): fails if a file under DIR includes MuJoCo or sim/.
include(${CMAKE_CURRENT_LIST_DIR}/CalibIsolation.cmake)
twinbench_check_calib_isolation(${DIR})
message(STATUS "calib isolation: no MuJoCo or sim/ include under ${DIR}")
