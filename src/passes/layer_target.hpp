// The off-screen layers the object's camera-match passes draw into
// (passes/object_blur, passes/object_bloom): an RGBA8 texture as a
// framebuffer's colour, with a 16-bit depth buffer where the object itself
// is drawn into it.
#pragma once

#include <string>

#include "gles/gl_objects.hpp"

namespace probelight::passes {

// A 16-bit depth renderbuffer of width_px x height_px.
gles::Renderbuffer makeDepthRenderbuffer(int width_px, int height_px);

// `texture` (RGBA8, LINEAR) and `framebuffer` with it as colour and `depth`
// (null: none) as depth. The caller's framebuffer binding is kept. False,
// with `error` naming `what`, when the GPU cannot make or complete it.
bool makeColourLayer(int width_px, int height_px, const gles::Renderbuffer* depth, const std::string& what,
                     gles::Texture& texture, gles::Framebuffer& framebuffer, std::string& error);

}  // namespace probelight::passes
