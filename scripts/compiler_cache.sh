# Sourced by the build scripts: every compiler they start (CMake's, and the example and consumer
# projects' the tests configure) goes through ccache when it is installed (scripts/setup installs
# it). Paths under the project root are hashed relative to it, so a fresh clone reuses the objects
# of earlier builds on the same machine. GAUSSTRACK_CCACHE=0 builds without it.
if [ "${GAUSSTRACK_CCACHE:-1}" = 1 ] && command -v ccache > /dev/null; then
  export CMAKE_CXX_COMPILER_LAUNCHER=ccache CMAKE_C_COMPILER_LAUNCHER=ccache
  export CCACHE_BASEDIR="$PWD" CCACHE_NOHASHDIR=true
fi
