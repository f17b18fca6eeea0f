// What the renderer draws: placed instances of parts, a floor, lights and a background.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "cad/core/schema.h"
#include "cad/part.h"
#include "render/image.h"
#include "render/lights.h"
#include "render/material.h"

namespace cadsynth {

// Colours are linear RGB in [0, 1].
struct Scene {
  // world_from_model of each placed part; an instance's own colour, if any, wins over its part's.
  std::vector<Instance> instances;
  std::vector<Eigen::Vector3f> part_colors;  // one per part; parts without one are light grey

  // Geometry that is seen but is not an object (a tote, a table, a jig): it shows in the colour
  // and depth images and hides what lies behind it, but has no instance id, pose or mask (its
  // pixels are 0 in the instance image, like the floor's).
  struct Fixture {
    std::string name;
    Mesh mesh;                                   // in the world frame, mm
    Eigen::Vector3f color{0.3f, 0.4f, 0.55f};    // sRGB, the fast mode's albedo
    Material material = DefaultMaterial(color);  // the pbr mode's
    // Sampled as the instances are where render.background_samples caps the rest: an object
    // that is not labelled but should look as an instance does (a distractor), not a container.
    bool object = false;
  };
  std::vector<Fixture> fixtures;

  bool floor = true;  // the plane z = 0, a square centred on the origin
  double floor_half_size_mm = 10000.0;
  Eigen::Vector3f floor_color{0.55f, 0.55f, 0.55f};
  Eigen::Vector3f background_color{0.12f, 0.14f, 0.18f};

  // Lambert shading: albedo * (ambient + sum of light intensity * max(0, n . l) * unshadowed).
  struct Light {
    enum class Kind { kDirectional, kPoint };
    Kind kind = Kind::kDirectional;
    Eigen::Vector3d direction{-0.3, -0.4, -1.0};  // directional: the way the light travels (world)
    Eigen::Vector3d position{0.0, 0.0, 2000.0};   // point: where it is (world, mm); no fall-off
    float intensity = 0.75f;

    // A recipe's light gives a direction (directional) or a position (point): its kind has no key
    // of its own, the reader sets it from which one is given.
    template <class Self, class Visit>
    static void Fields(Self& o, Visit&& visit) {
      visit(o.kind, Field{.kind = "choice",
                          .doc = "directional (a direction given) or point (a position given)",
                          .choices = {"directional", "point"},
                          .internal_name = "kind"});
      visit(o.direction, Field{"direction", "vector3", "directional: the way the light travels"});
      visit(o.position, Field{"position", "length3", "a point light (no fall-off)"});
      visit(o.intensity, Field{.key = "intensity",
                               .kind = "number",
                               .doc = "its weight",
                               .range = Range::kNonNegative});
    }
  };
  std::vector<Light> lights = {Light{}};
  float ambient = 0.3f;
  bool shadows = true;  // hard shadows: an occlusion ray from every lit point to every light

  // The look options above, the recipe's `render` keys (the fast mode's), and only those: a Scene
  // is also what a run draws (instances, fixtures, the pbr mode's materials, lights and
  // environment), which the run key takes from what prepare made (KeyPrepared) or from their own
  // descriptions (Material, LightSource, Environment). Called Fields rather than LookFields so
  // that every visitor (the recipe reader and tree, the run key, the tests) takes a Scene as it
  // takes any described options. `lights` describe their own (Light::Fields).
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.background_color, Field{"background", "color", "fast: where nothing is hit (sRGB)"});
    visit(o.floor, Field{"floor", "bool", "a floor under the parts"});
    visit(o.floor_color, Field{"floor_color", "color", "the floor's colour (sRGB)"});
    visit(o.ambient, Field{.key = "ambient",
                           .kind = "number",
                           .doc = "fast: ambient light",
                           .range = Range::kNonNegative});
    visit(o.shadows, Field{"shadows", "bool", "fast: hard shadows"});
    visit(o.floor_half_size_mm, Field{.kind = "length",
                                      .doc = "the floor square's half side",
                                      .internal_name = "floor_half_size"});
  }

  // The physically based mode (RenderOptions::mode pbr) shades with these instead of the colours,
  // lights, ambient and background above. Depth and every label are the same in both modes.
  // Per instance, an index into `materials`; empty, or -1 for an instance: a plastic-like
  // dielectric of the instance's colour (DefaultMaterial).
  std::vector<int> instance_material;
  std::vector<Material> materials;
  Material floor_material = DefaultFloorMaterial(floor_color);
  std::vector<LightSource> light_sources = DefaultLightSources();
  Environment environment;

  // Instance i's colour (sRGB): its own, else its part's, else light grey (0.7).
  Eigen::Vector3f InstanceColor(size_t i) const;
  // Instance i's material in the pbr mode as the renderer shades it (before any randomisation):
  // its assigned one, or DefaultMaterial of its colour, with a base colour taken from the part
  // (Material::base_from_part) resolved to the instance's colour, linear. Throws if
  // instance_material names a missing material.
  Material InstanceMaterial(size_t i) const;

  // A dielectric of base colour `srgb` (CAD colours are sRGB), roughness 0.45, specular 0.5.
  static Material DefaultMaterial(const Eigen::Vector3f& srgb);
  static Material DefaultFloorMaterial(const Eigen::Vector3f& srgb);
  // A work cell's ceiling light: a 1 m x 1 m rect light 2 m above the origin facing down, 51 W
  // (Blender's area-light watts: radiance 51 / 4 = 12.75 W/(m2 sr); the floor under it receives
  // about 12.75 x 1 / 2^2 = 3.2 W/m2).
  static std::vector<LightSource> DefaultLightSources();
};

// One frame's appearance in the physically based mode (domain randomisation, render/randomize.h):
// what the path tracer shades with instead of the Scene's materials, lights and environment, and
// the camera's exposure and white balance. The exact depth and every label are unchanged by it (a
// depth sensor model's depth is not: its projector's return goes through the frame's materials).
struct FrameLook {
  std::vector<Material> instance_materials;  // one per instance, base colours resolved (linear)
  // The instances' own colours (linear; the CAD colour or the palette's), for presets that take
  // the part's colour (Material::base_from_part). The renderer does not read them.
  std::vector<Eigen::Vector3f> instance_colors;
  Material floor;
  std::vector<Material> fixture_materials;  // one per fixture
  std::vector<LightSource> lights;
  Environment environment;
  double exposure = 0.0;  // stops, added to RenderOptions::exposure
  Eigen::Vector3f white_balance = Eigen::Vector3f::Ones();  // gains on the linear colour
  // A photo the colour (and grey) image shows where the pixel's centre ray hits nothing (the
  // render-and-paste baseline): scaled to cover the image and centred, pasted after the display
  // transform, without the sensor's noise. Null: none.
  std::shared_ptr<const LinearImage> background;
};

// A palette of well-separated colours for parts without a colour of their own.
Eigen::Vector3f PaletteColor(int index);

}  // namespace cadsynth
