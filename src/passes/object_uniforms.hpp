// Uniforms every object program shares: where the calibrated camera puts a
// point of W (camera_projection.glsl's inputs, as sphere_object.vert,
// mesh_object.vert and model_object.vert read them) and the environment
// maps' samplers (cube_storage.glsl's face size and scale).
#pragma once

#include "core/types.hpp"
#include "gles/gl_objects.hpp"
#include "passes/environment_maps.hpp"

namespace probelight::passes {

// u_rotation_cam_from_world, u_translation_cam_from_world, u_eye_w,
// u_distortion, u_distortion_k3, u_focal_px, u_principal_px,
// u_image_size_px and u_depth_range_m (near, far). `program` must be in use.
void setCameraProjectionUniforms(const gles::Program& program, const CameraIntrinsics& camera,
                                 const PoseCamFromWorld& pose, double near_m, double far_m);

// Binds `map` to texture unit `unit` as <prefix>_map, with <prefix>_face_size
// and <prefix>_scale ("u_diffuse" -> u_diffuse_map, ...). Leaves `unit` active.
void bindCubeMapUniforms(const gles::Program& program, const std::string& prefix, const GpuCubeMap& map, int unit);

}  // namespace probelight::passes
