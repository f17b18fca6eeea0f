#include "render/scene.h"

#include <cmath>

#include "cad/core/error.h"
#include "render/image.h"

namespace cadsynth {

Eigen::Vector3f Scene::InstanceColor(size_t i) const {
  const Instance& instance = instances.at(i);
  const size_t part = static_cast<size_t>(instance.part);
  return instance.color              ? *instance.color
         : part < part_colors.size() ? part_colors[part]
                                     : Eigen::Vector3f(0.7f, 0.7f, 0.7f);
}

Material Scene::InstanceMaterial(size_t i) const {
  const Eigen::Vector3f srgb = InstanceColor(i);
  const int m = i < instance_material.size() ? instance_material[i] : -1;
  if (m >= static_cast<int>(materials.size()))
    throw Error("renderer: instance '" + instances[i].name + "' refers to a missing material");
  Material material = m < 0 ? DefaultMaterial(srgb) : materials[static_cast<size_t>(m)];
  // Part colours are sRGB (CAD files and the palette); materials take linear colours.
  if (material.base_from_part) {
    for (int c = 0; c < 3; ++c) material.surface.base_color[c] = SrgbToLinear(srgb[c]);
  }
  return material;
}

Material Scene::DefaultMaterial(const Eigen::Vector3f& srgb) {
  Material m;
  for (int c = 0; c < 3; ++c) m.surface.base_color[c] = SrgbToLinear(srgb[c]);
  m.surface.metallic = 0.0f;
  m.surface.roughness = 0.45f;
  m.surface.specular = 0.5f;
  m.base_from_part = true;
  return m;
}

Material Scene::DefaultFloorMaterial(const Eigen::Vector3f& srgb) {
  Material m = DefaultMaterial(srgb);
  m.surface.roughness = 0.8f;
  m.base_from_part = false;
  return m;
}

std::vector<LightSource> Scene::DefaultLightSources() {
  LightSource ceiling;
  ceiling.kind = LightSource::Kind::kRect;
  ceiling.position = {0.0, 0.0, 2000.0};
  ceiling.direction = {0.0, 0.0, -1.0};
  ceiling.size_x_mm = ceiling.size_y_mm = 1000.0;
  ceiling.power = 51.0;
  return {ceiling};
}

Eigen::Vector3f PaletteColor(int index) {
  // Hues spread by the golden angle, fairly saturated, never grey (the floor is grey).
  const float hue = std::fmod(0.08f + 0.61803398875f * static_cast<float>(index), 1.0f) * 6.0f;
  const float s = 0.65f, v = 0.9f;
  const int sector = static_cast<int>(hue) % 6;
  const float f = hue - std::floor(hue);
  const float p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  switch (sector) {
    case 0:
      return {v, t, p};
    case 1:
      return {q, v, p};
    case 2:
      return {p, v, t};
    case 3:
      return {p, q, v};
    case 4:
      return {t, p, v};
    default:
      return {v, p, q};
  }
}

}  // namespace cadsynth
