# Run at build time (cmake -P) by the twinbench_completion target: writes OUT, the bash
# completion script that `EXE completion bash` prints (bench/cli_completion.h); fails the build
# if the binary fails. In: EXE (the built twinbench), OUT (the script's path).
# Leak checking off: a sanitizer build (TWINBENCH_SANITIZERS) runs it too, without the test
# scripts' suppressions of the system libraries.
execute_process(COMMAND ${CMAKE_COMMAND} -E env ASAN_OPTIONS=detect_leaks=0
                        "${EXE}" completion bash OUTPUT_VARIABLE _script
                RESULT_VARIABLE _rc ERROR_VARIABLE _err)
if(NOT _rc EQUAL 0 OR NOT _script MATCHES "complete -o filenames")
  message(FATAL_ERROR "${EXE} completion bash failed (${_rc}): ${_err}")
endif()
file(WRITE "${OUT}" "${_script}")
