#include "stages/scene_object.hpp"

#include "ibl/metallic_roughness.hpp"
#include "model/gltf_loader.hpp"
#include "passes/model_renderer.hpp"
#include "stages/stage_settings.hpp"

namespace probelight {

bool SceneObject::readsGlossy(const std::vector<double>& glossy_exponents) const {
  if (model) return modelReadsGlossy(*model, glossy_exponents);
  return !glossy_exponents.empty() && ibl::needsGlossy(material);
}

SceneObject modelSceneObject(std::shared_ptr<const model::MeshModel> model, const model::ModelPlacement& placement) {
  SceneObject object;
  object.world_from_model = model::worldFromModel(*model, placement);
  auto triangles = std::make_shared<std::vector<glm::vec3>>();
  triangles->reserve(model->triangleCount() * 3);
  for (const model::Primitive& primitive : model->primitives)
    for (std::size_t i = 0; i + 2 < primitive.indices.size(); i += 3)
      for (std::size_t k = 0; k < 3; ++k)
        triangles->push_back(glm::vec3(object.world_from_model *
                                       glm::dvec4(glm::dvec3(primitive.positions_m[primitive.indices[i + k]]), 1.0)));
  const model::BoundingSphere bound = model::placedBoundingSphere(*model, object.world_from_model);
  object.shape.shape = ibl::ShadowCaster::Shape::kMesh;
  object.shape.position_w = placement.position_m;
  object.shape.mesh_triangles_w = std::move(triangles);
  object.shape.mesh_centre_w = bound.centre_w;
  object.shape.mesh_radius_m = bound.radius_m;
  object.model = std::move(model);
  return object;
}

Status sceneObjectFromConfig(const PipelineSettings& settings, SceneObject& object) {
  const ObjectConfig& config = settings.object;
  if (config.model_path.empty()) {
    object = SceneObject{};
    object.shape.position_w = config.position_w;
    object.shape.radius_m = config.radius_m;
    object.material = objectMaterial(settings);
    return Status::ok();
  }
  auto model = std::make_shared<model::MeshModel>();
  std::string error;
  if (!model::loadGltfModel(config.model_path, {}, *model, error)) return Status::badInput(error);
  object = modelSceneObject(std::move(model), {config.position_w, glm::radians(config.yaw_deg), config.scale});
  return Status::ok();
}

bool modelReadsGlossy(const model::MeshModel& model, const std::vector<double>& glossy_exponents) {
  if (glossy_exponents.empty()) return false;
  const std::vector<double> alphas = ibl::specularRungAlphas(glossy_exponents);
  const int diffuse_rung = static_cast<int>(alphas.size()) - 1;
  std::vector<model::Material> materials = model.materials;
  materials.emplace_back();  // glTF's default, for primitives without one
  for (const model::Material& material : materials) {
    const auto [lowest, highest] = passes::materialRoughnessRange(material, model);
    const ibl::RungRange range = ibl::specularRungRange(lowest, highest, alphas);
    // A glossy rung lies strictly between the mirror (0) and the diffuse map.
    for (int rung = range.first; rung <= range.last; ++rung)
      if (rung > 0 && rung < diffuse_rung) return true;
  }
  return false;
}

}  // namespace probelight
