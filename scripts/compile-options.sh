# Sourced by scripts/build.sh, scripts/test-sanitizers.sh and
# scripts/cross-build-arm64 (from the repository root): the CMake options
# that make a build cheaper, in compile_cmake_args, and the generator for a
# build folder (generator_args BUILD_DIR).
#
# Ninja, where it is installed, for a build folder made now (a folder keeps
# the generator it was configured with): it starts a target's compiles
# while the libraries it links are still being built, so both cores stay
# busy through the chain of libraries.
#
# ccache, where it is installed (scripts/install-deps.sh installs it): a
# second build of the same sources is mostly cache hits. Paths under the
# clone are hashed relative to it, and the compiler's working folder is left
# out of the hash, so that a clone in another folder hits the same entries.
#
# PROBELIGHT_UNITY_BUILD=ON (CI sets it): CMake's unity build, 8 sources of
# a target compiled as one translation unit, so that the headers they share
# (OpenCV, GoogleTest, GLM, CLI11) are parsed once, not 8 times: a build
# from nothing takes about two thirds of the compile time (the release
# build measured 8.9 core-min against about 14). An edited file recompiles
# its whole batch, so a developer's build leaves it off (the default). It
# needs file-local names that differ between the files of a target; CI's
# build is the check. A batch names its sources by absolute path, so its
# cache entries serve a later clone in the same folder only.
compile_cmake_args=("-DCMAKE_UNITY_BUILD=${PROBELIGHT_UNITY_BUILD:-OFF}" -DCMAKE_UNITY_BUILD_BATCH_SIZE=8)
if command -v ccache >/dev/null; then
  compile_cmake_args+=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  export CCACHE_BASEDIR=$PWD CCACHE_NOHASHDIR=1
fi
generator_args=()
generator_for() {  # generator_for BUILD_DIR: sets generator_args
  generator_args=()
  if [[ ! -f $1/CMakeCache.txt ]] && command -v ninja >/dev/null; then generator_args=(-G Ninja); fi
}
