# Sourced by scripts/build.sh, scripts/test-sanitizers.sh and
# scripts/cross-build-arm64 (from the repository root): compiles go
# through ccache where it is installed (scripts/install-deps.sh installs
# it), so a second build of the same sources is mostly cache hits.
# Paths under the clone are hashed relative to it, and the compiler's
# working folder is left out of the hash, so that a clone in another folder
# (CI's next run) hits the same entries.
ccache_cmake_args=()
if command -v ccache >/dev/null; then
  ccache_cmake_args=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  export CCACHE_BASEDIR=$PWD CCACHE_NOHASHDIR=1
fi
