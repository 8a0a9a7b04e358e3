// The virtual object the kiosk shows: a built-in shape (a sphere or a box,
// with the seeds' Blinn-Phong material) or a user's glTF model with its own
// materials, and where it stands on the ground of W. One description feeds
// the maps (which levels its materials read), the shadows (what casts them)
// and the compose stage (what is drawn).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/status.hpp"
#include "stages/pipeline_settings.hpp"

#include "ibl/ground_shadow.hpp"
#include "ibl/surface_shading.hpp"
#include "model/mesh_model.hpp"
#include "model/model_placement.hpp"

namespace probelight {

struct SceneObject {
  ibl::ShadowCaster shape;        // kMesh for a model
  ibl::SurfaceMaterial material;  // the built-in shapes' material
  std::shared_ptr<const model::MeshModel> model;  // set for a model
  glm::dmat4 world_from_model{1.0};

  bool isModel() const { return model != nullptr; }
  // Whether its materials read a glossy map of a ladder with these glossy
  // maps (sharpest first): the maps stage makes them only then.
  bool readsGlossy(const std::vector<double>& glossy_exponents) const;
};

// A model placed on the tag (model::worldFromModel): its triangles in W cast
// the shadow, its bounding sphere bounds the shadow maps.
SceneObject modelSceneObject(std::shared_ptr<const model::MeshModel> model, const model::ModelPlacement& placement);

// probelight.yaml's `object`: the sphere with its material, or the model
// object.model names, loaded (model/gltf_loader.hpp: a bad file is a
// bad-input Status whose one line names the file and the field) and placed.
Status sceneObjectFromConfig(const PipelineSettings& settings, SceneObject& object);

// Whether some material of `model` has a roughness, over its texture, that
// reaches a glossy rung of the ladder (ibl/metallic_roughness.hpp).
bool modelReadsGlossy(const model::MeshModel& model, const std::vector<double>& glossy_exponents);

}  // namespace probelight
