# Run at build time (cmake -P) by the twinbench_version target: writes OUT, a header with the
# project version and `git describe` of the source tree, and rewrites it only when that text
# changed, so a build after a commit relinks twinbench and nothing else recompiles.
# In: SRC (source tree), OUT (header path), VERSION (CMake's project version).
set(_describe "unknown")
find_package(Git QUIET)
if(GIT_FOUND AND EXISTS "${SRC}/.git")
  execute_process(COMMAND ${GIT_EXECUTABLE} describe --always --dirty --tags
                  WORKING_DIRECTORY "${SRC}" OUTPUT_VARIABLE _out RESULT_VARIABLE _rc
                  ERROR_QUIET OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(_rc EQUAL 0 AND NOT _out STREQUAL "")
    set(_describe "${_out}")
  endif()
endif()
set(_text "// Written by cmake/WriteVersion.cmake at build time; not in the source tree.
#pragma once
#define TWINBENCH_VERSION \"${VERSION}\"
#define TWINBENCH_GIT_DESCRIBE \"${_describe}\"
")
set(_old "")
if(EXISTS "${OUT}")
  file(READ "${OUT}" _old)
endif()
if(NOT _old STREQUAL _text)
  file(WRITE "${OUT}" "${_text}")
endif()
