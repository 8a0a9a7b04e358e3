# Sourced: the GPU contexts the tests run under besides this machine's own,
# made by Mesa itself (its version and extension overrides), so the probe
# (gles/capabilities.cpp) reads them from the driver as on a board.
#
#   pi4    V3D 4.2 under Mesa's v3d driver, as read from Mesa's source (not
#          measured on a board): ES 3.1, no EXT_color_buffer_half_float (the
#          maps render RGBA16F through EXT_color_buffer_float), no linear
#          filtering of 32-bit float textures. Not emulated: its 4096 px
#          texture limit and 4 draw buffers (the kiosk's textures and targets
#          stay under both), and its 32-bit mediump (llvmpipe's is 32-bit
#          too; the shaders' 16-bit twins are tests/gles/mediump_test.cpp).
#   gles2  a bare OpenGL ES 2.0 context: no float or depth textures and none
#          of the optional extensions the code has a path without, so every
#          8-bit and fallback path runs. OES_texture_npot stays: without it
#          Mesa refuses every non-power-of-two texture, where GLES2 itself
#          allows them without mipmaps or REPEAT (which the code keeps to).
#          Mesa cannot take away OES_depth_texture, EXT_unpack_subimage or
#          OES_element_index_uint: the tests' in-process mask
#          (Capabilities::withoutExtensions) runs the paths without those.
#
# usage: (gpu_profile_export NAME; COMMAND)   exports the profile's variables,
#        in a subshell so that they end with it
gpu_profile_export() {
  case "$1" in
    pi4)
      export MESA_GLES_VERSION_OVERRIDE=3.1
      export MESA_EXTENSION_OVERRIDE="-GL_EXT_color_buffer_half_float -GL_OES_texture_float_linear"
      ;;
    gles2)
      export MESA_GLES_VERSION_OVERRIDE=2.0
      export MESA_EXTENSION_OVERRIDE="-GL_OES_texture_half_float -GL_OES_texture_half_float_linear \
-GL_EXT_color_buffer_half_float -GL_OES_texture_float -GL_OES_texture_float_linear -GL_OES_standard_derivatives"
      ;;
    *) echo "gpu_profile_export: no profile '$1' (pi4, gles2)" >&2; return 2 ;;
  esac
}
