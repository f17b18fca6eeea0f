#include "recipes/reference.h"

#include <cmath>
#include <sstream>
#include <type_traits>

#include "cad/schema.h"
#include "cad/shape.h"
#include "dataset/bop.h"
#include "recipes/recipe.h"
#include "render/renderer.h"
#include "render/sensor.h"
#include "variants/arrangement.h"

namespace cadsynth {
namespace {

template <typename Options>
void Section(std::ostringstream& out, const char* name, const char* what) {
  out << name << ":  # " << what << "\n";
  const Options defaults;
  Options::Fields(defaults, [&out](const auto& value, const Field& field) {
    if (field.key.empty()) return;
    std::string line = "  " + std::string(field.key) + ": ";
    if constexpr (std::is_floating_point_v<std::decay_t<decltype(value)>>) {
      if (field.kind == "angle") {
        line += FieldText(std::round(value * 180.0 / M_PI * 1e6) / 1e6, field) + " deg";
      } else {
        line += FieldText(value, field) + (field.kind == "length" ? " mm" : "");
      }
    } else {
      line += FieldText(value, field);
    }
    line.resize(std::max<size_t>(line.size() + 1, 34), ' ');
    out << line << "# " << field.kind;
    if (!field.choices.empty()) {
      out << " (";
      for (size_t i = 0; i < field.choices.size(); ++i) out << (i ? " | " : "") << field.choices[i];
      out << ")";
    }
    out << ": " << field.doc << "\n";
  });
}

}  // namespace

std::string RecipeReference() {
  std::ostringstream out;
  out << "# The recipe keys whose options are described once in the code (cad/schema.h), with "
         "their\n"
         "# defaults; lengths take a unit (mm, cm, m, in), a bare number is mm. README's "
         "\"Recipes\"\n"
         "# section has every section with examples.\n";
  Section<BopOptions>(
      out, "output",
      "dataset layout and formats; also dir (the output folder), formats: [bop, coco, paper, "
      "pvn3d, grasp] and rgb: png | jpg");
  Section<ArrangementOptions>(
      out, "scene",
      "how the parts lie on the floor; with parts: at the top level, or per entry of scenes: "
      "[{name, parts, and these keys}]");
  Section<TessellationOptions>(out, "tessellation",
                               "how B-rep surfaces become triangles; also crease_angle (meshes)");
  Section<RenderOptions>(
      out, "render",
      "ray casting; also background, floor, floor_color, ambient, lights, shadows, colors (the "
      "fast mode's look); mode: pbr reads the materials: {floor, default, assign: [{name|family|"
      "file, preset, base_color, metallic, roughness, specular, anisotropic, clearcoat, "
      "clearcoat_roughness, distribution: ggx|multiscatter_ggx, tangent: radial|x, texture}]} "
      "(colours linear [r, g, b] or sRGB \"#RRGGBB\") and "
      "lighting: {lights: [{type: point|spot|rect|disc|sun, ...}], environment: {type: "
      "uniform|sky|image, ...}} sections (README, \"Physically based mode\")");
  Section<DepthModel>(
      out, "camera.depth",
      "the depth sensor model (a name, or a map); the model's published defaults fill the keys "
      "not given (README, \"Depth sensors\"); camera also takes image: rgb | gray | gray16; "
      "cameras: [{name, position, look_at | rotation, and the camera keys}] is a rig of named "
      "sensors moved together (README, \"Camera rigs\")");
  Section<ImageSensor>(
      out, "camera.imager",
      "the image sensor and lens of the colour or grey camera: shot and read noise "
      "(Poisson-Gaussian) and cos^4 vignetting (README, \"Image sensor\")");
  Section<Distortion>(out, "camera.distortion",
                      "OpenCV's lens distortion (k1, k2, p1, p2, k3): the image, masks and depth "
                      "are rendered through it, and the coefficients written beside cam_K "
                      "(README, \"Lens effects\")");
  Section<ThinLens>(out, "camera.lens",
                    "depth of field, pbr only; camera.motion: {velocity_mm_s: [x, y, z], "
                    "angular_velocity_deg_s: [x, y, z], exposure_ms} in the camera's frame is "
                    "motion blur (README, \"Lens effects\")");
  Section<RunLimits>(out, "limits",
                     "how much work a recipe may ask for (raise them if you mean it)");
  return out.str();
}

}  // namespace cadsynth
