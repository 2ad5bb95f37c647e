# Compiles through ccache where it is installed (scripts/install_deps.sh installs Debian's), so a
# rebuild of unchanged sources, in a clean clone too, costs a cache lookup instead of a compile.
# The cache lives outside the source tree (ccache's default ~/.cache/ccache, or CCACHE_DIR), so
# the clones on one machine share it: CCACHE_BASEDIR makes the absolute paths under the source
# tree relative, and CCACHE_NOHASHDIR leaves the build folder out of the hash, so two clones in
# different folders compile to the same cache entries. TWINBENCH_CCACHE=OFF turns it off.
option(TWINBENCH_CCACHE "Compile through ccache when it is installed" ON)
if(TWINBENCH_CCACHE AND NOT CMAKE_CXX_COMPILER_LAUNCHER)
  find_program(TWINBENCH_CCACHE_PROGRAM ccache)
  if(TWINBENCH_CCACHE_PROGRAM)
    set(CMAKE_CXX_COMPILER_LAUNCHER
        ${CMAKE_COMMAND} -E env CCACHE_BASEDIR=${CMAKE_SOURCE_DIR} CCACHE_NOHASHDIR=true
        ${TWINBENCH_CCACHE_PROGRAM})
  endif()
endif()
