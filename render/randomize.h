// Domain randomisation (the recipe's `randomize:` section): every frame (or every scene) drawn
// with its own materials, lights, environment and camera settings from distributions the recipe
// gives, as a fixed function of (seed, scene, view, what is drawn).
//
// Every quantity has its own stream: its draws hash (seed, scene, frame or scene, the quantity's
// name, an index), so adding or changing one distribution moves no other draw, any thread count,
// shard or resumed run draws the same numbers, and a frame can be drawn again from its key alone.
// Every draw is recorded (`Drawn`) under the quantity's name: the run writes them per frame to
// scene_randomization.json so that a bad frame's settings can be found and ablated.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "cad/core/schema.h"
#include "render/camera.h"
#include "render/lights.h"
#include "render/material.h"
#include "render/scene.h"
#include "render/sensor.h"

namespace cadsynth {

// A distribution of one number.
struct Distribution {
  enum class Kind {
    kFixed,       // always a
    kUniform,     // uniform on [a, b]
    kNormal,      // normal of mean a and standard deviation b
    kLogUniform,  // log-uniform on [a, b], 0 < a: intensities, scales
    kChoice,      // one of `values`, equally likely
  };
  Kind kind = Kind::kFixed;
  double a = 0.0, b = 0.0;
  std::vector<double> values;

  static Distribution Fixed(double v) { return {Kind::kFixed, v, v, {}}; }
  static Distribution Uniform(double lo, double hi) { return {Kind::kUniform, lo, hi, {}}; }
  bool Check(std::string* why) const;
  // The draw of stream `stream` (cad/core/random.h UniformDraw) for `seed`: uniform, log-uniform
  // and choice by the inverse CDF of draw 0, normal by Box-Muller from draws 0 and 1.
  double Draw(uint64_t seed, const std::string& stream) const;
  // The smallest and largest value a draw can take; a normal's mean (where a quantity has a
  // range, the tails of a normal are clipped to it).
  double Lowest() const;
  double Highest() const;
  bool operator==(const Distribution&) const = default;

  // As a recipe writes it (cad/core/schema.h FieldText): the value, {uniform | normal |
  // log_uniform: [a, b]} or {choice: [values]}, numbers exactly (lengths in mm: bare numbers).
  std::string Text() const {
    const auto number = [](double v) { return FieldText(v, Field{}); };
    if (kind == Kind::kFixed) return number(a);
    std::string list;
    if (kind == Kind::kChoice) {
      for (size_t i = 0; i < values.size(); ++i) list += (i ? ", " : "") + number(values[i]);
    } else {
      list = number(a) + ", " + number(b);
    }
    const char* name = kind == Kind::kUniform  ? "uniform"
                       : kind == Kind::kNormal ? "normal"
                       : kind == Kind::kChoice ? "choice"
                                               : "log_uniform";
    std::string text = "{";  // (appended: GCC 12 warns falsely on "{" + std::string&&)
    text.append(name).append(": [").append(list).append("]}");
    return text;
  }
};

// A light kind's name as recipes and randomisation records write it ("rect").
const char* LightKindName(LightSource::Kind kind);

// How often a group's quantities are drawn anew: every frame, or once per scene (all its frames
// share the draw).
enum class DrawPer { kFrame, kScene };

// The field of a group's DrawPer: the recipe key `per` of the group's section (`key` where the
// struct holds that section's keys, else empty and `name` for the run key).
inline Field DrawPerField(std::string_view key, std::string_view name = {}) {
  return Field{.key = key,
               .kind = "choice",
               .doc = "how often it is drawn",
               .choices = {"frame", "scene"},
               .internal_name = name};
}

// A surface's material redrawn around its own: a preset picked from `presets` (none: keep the
// material), an image texture picked from `textures` (none: keep the texture), its base colour
// jittered in HSV (sRGB, as a colour picker shows it: `hue` added in turns, `saturation` and
// `value` multiplied), and the Principled parameters and the texture's feature size (a factor)
// drawn. Unset distributions leave the value as it is.
struct MaterialRandomization {
  std::vector<Material> presets;
  std::vector<std::string> preset_names;  // one per preset, for the record
  // Image textures to pick from (after the preset; each an image Texture with its pixels), and
  // their file names for the record.
  std::vector<Texture> textures;
  std::vector<std::string> texture_names;
  std::optional<Distribution> hue, saturation, value;
  std::optional<Distribution> metallic, roughness, specular, texture_scale;
  bool Check(std::string* why) const;

  // The presets are picked by name (read by hand: each must be a preset); the textures come from
  // a folder (`textures: {folder, scale}`, read by hand, keyed by their files).
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.preset_names,
          Field{.key = "preset", .kind = "names", .doc = "presets to pick from", .by_hand = true});
    visit(o.hue, Field{"hue", "distribution", "hue shift (turns)"});
    visit(o.saturation, Field{"saturation", "distribution", "saturation factor"});
    visit(o.value, Field{"value", "distribution", "value (brightness) factor"});
    visit(o.metallic, Field{"metallic", "distribution", "metallic (0-1)"});
    visit(o.roughness, Field{"roughness", "distribution", "roughness (0-1)"});
    visit(o.specular, Field{"specular", "distribution", "specular (0-1)"});
    visit(o.texture_scale, Field{"texture_scale", "distribution", "factor on the texture's scale"});
  }
};

// Parts the rule matches (by name, family or file; the run resolves which instances) get a
// material drawn once per part (every copy alike) or once per instance.
struct PartRandomization {
  MaterialRandomization material;
  bool per_instance = false;
  DrawPer per = DrawPer::kFrame;
  std::string where;  // the rule's place in the recipe, for messages

  // Its own keys; the material's are MaterialRandomization's, the patterns the rule's.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.per_instance,
          Field{"each", "choice", "one draw per part or per instance", {"part", "instance"}});
    visit(o.per, DrawPerField("per"));
  }
};

// Lights on a shell about the scene: `count` lights of a kind picked from `kinds`, each at an
// elevation (degrees above the floor) and azimuth (degrees) on a sphere of radius `distance`
// (mm) about the scene's centre, aimed at it, of `power` W (Blender's), with the colour of a
// black body at `temperature` kelvin (render/randomize.h BlackbodyColor) and `size` (mm: a
// rect's side, a disc's diameter, a sphere light's diameter). They replace the recipe's lights
// unless `keep` is set.
struct LightRandomization {
  Distribution count = Distribution::Fixed(1);
  std::vector<LightSource::Kind> kinds = {LightSource::Kind::kRect};
  Distribution elevation_deg = Distribution::Uniform(30, 90);
  Distribution azimuth_deg = Distribution::Uniform(0, 360);
  Distribution distance_mm = Distribution::Uniform(1200, 2500);
  Distribution power = {Distribution::Kind::kLogUniform, 10, 200, {}};
  Distribution temperature_k = Distribution::Uniform(3500, 6500);
  Distribution size_mm = Distribution::Uniform(200, 1000);
  bool keep = false;
  bool Check(std::string* why) const;

  // `type` is a list of names (read by hand); `per` is Randomization::lights_per.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.count, Field{"count", "distribution", "how many"});
    visit(o.kinds, Field{.key = "type",
                         .kind = "names",
                         .doc = "point, spot, rect, disc",
                         .choices = {"point", "spot", "rect", "disc"},
                         .by_hand = true});
    visit(o.elevation_deg, Field{"elevation", "distribution", "degrees above the floor"});
    visit(o.azimuth_deg, Field{"azimuth", "distribution", "degrees about the vertical"});
    visit(o.distance_mm, Field{"distance", "distribution_length", "from the scene's centre"});
    visit(o.power, Field{"power", "distribution", "W, as Blender's"});
    visit(o.temperature_k, Field{"temperature", "distribution", "colour temperature (K)"});
    visit(o.size_mm, Field{"size", "distribution_length", "area lights' size"});
    visit(o.keep, Field{"keep", "bool", "keep the recipe's own lights too"});
  }
};

// Images picked from a folder, equally likely (each with its pixels, read once), and their file
// names for the record.
struct ImageChoice {
  std::vector<std::filesystem::path> files;
  std::vector<std::shared_ptr<const LinearImage>> pixels;
  std::vector<std::string> names;
  bool Check(std::string* why) const;
};

// The environment's image (picked from `images`: the world becomes that equirectangular image),
// strength (absolute), rotation about z (degrees; image worlds), and, for uniform ones, a colour
// temperature (kelvin) of its colour.
struct EnvironmentRandomization {
  std::optional<ImageChoice> images;
  std::optional<Distribution> strength, rotation_deg, temperature_k;
  bool Check(std::string* why) const;

  // `images: {folder}` is read by hand (keyed by its files); `per` is
  // Randomization::environment_per.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.strength, Field{"strength", "distribution", "factor on the world's strength"});
    visit(o.rotation_deg, Field{"rotation", "distribution", "degrees about the vertical"});
    visit(o.temperature_k, Field{"temperature", "distribution", "colour temperature (K)"});
  }
};

// Background photos (FrameLook::background) picked from a folder: the render pasted over a photo
// where nothing is hit.
struct BackgroundRandomization {
  ImageChoice images;
  bool Check(std::string* why) const { return images.Check(why); }
};

// The camera: exposure (stops added to render.exposure), white balance (the kelvin the camera
// is balanced for: light of that temperature reads as a 6,504 K black body, D65's temperature,
// reads unbalanced), a noise gain (ISO: multiplies
// the image noise's standard deviation; needs camera.imager.full_well), the lens's focus
// distance (mm) and f-number (needs camera.lens), and a small jitter of its pose: a rotation by
// `rotation_deg` about a random axis through the camera and a shift by `translation_mm` in a
// random direction (the labels follow the jittered pose).
struct CameraRandomization {
  // noise_gain's range (draws are clipped to it).
  static constexpr double kMinNoiseGain = 0.05, kMaxNoiseGain = 20.0;
  std::optional<Distribution> exposure, white_balance_k, noise_gain, focus_distance_mm, f_number;
  std::optional<Distribution> rotation_deg, translation_mm;
  bool Check(std::string* why) const;

  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.exposure, Field{"exposure", "distribution", "stops"});
    visit(o.white_balance_k, Field{"white_balance", "distribution", "K"});
    visit(o.noise_gain, Field{"noise_gain", "distribution", "factor on the image noise"});
    visit(o.focus_distance_mm, Field{"focus_distance", "distribution_length", "the lens's focus"});
    visit(o.f_number, Field{"f_number", "distribution", "the lens's aperture"});
    visit(o.rotation_deg, Field{"rotation", "distribution", "degrees of pose jitter"});
    visit(o.translation_mm, Field{"translation", "distribution_length", "pose jitter"});
  }
};

// One recorded draw: the quantity's name (dotted, e.g. "part.2.roughness", "light.0.power",
// "camera.exposure") and its value (numbers, or a name for a picked preset or light type).
struct Drawn {
  std::string key;
  std::vector<double> values;
  std::string text;
};

// Distractors: objects that are not targets (no instance id, no labels; they occlude the targets
// and show in the images and the depth), `count` of them per scene, each an object picked
// uniformly from the run's list (primitives, files, family variants: DrawDistractors gets their
// number), a primitive's sides (box), diameter and height (cylinder) or diameter (sphere) drawn
// from `size_mm`, and a colour drawn uniformly in HSV (sRGB: any hue, saturation 0.1-0.9, value
// 0.15-0.9). Being geometry, they are drawn once per scene: the run drops them among the parts
// with the scene's physics. Their materials are redrawn per frame or per scene from `material`
// (each distractor on its own) when it is set.
struct DistractorRandomization {
  static constexpr int kMaxCount = 200;
  Distribution count = Distribution::Uniform(3, 8);
  Distribution size_mm = Distribution::Uniform(20, 80);
  std::optional<MaterialRandomization> material;
  DrawPer material_per = DrawPer::kFrame;
  bool Check(std::string* why) const;

  // `objects` is the run's (RandomizeSpec::distractor_objects), `material` a section of its own
  // (MaterialRandomization) whose `per` is material_per.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.count, Field{"count", "distribution", "how many"});
    visit(o.size_mm, Field{"size", "distribution_length", "their size"});
    visit(o.material_per, DrawPerField("", "material_per"));
  }
};

// One distractor of a scene: the object picked (an index into the run's list), the primitive's
// three sizes (mm; the run uses the ones its kind needs) and its colour (sRGB).
struct DistractorPick {
  int object = 0;
  Eigen::Vector3d size_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3f color = Eigen::Vector3f::Constant(0.5f);
};

// A scene's randomisation. Groups left unset are not randomised.
struct Randomization {
  uint64_t seed = 0;
  std::vector<PartRandomization> parts;
  // Per instance, the rule in `parts` that draws its material, or -1, and its part (filled in
  // by the run).
  std::vector<int> instance_rule, instance_part;
  std::optional<MaterialRandomization> floor, fixtures;
  DrawPer floor_per = DrawPer::kFrame, fixtures_per = DrawPer::kFrame;
  std::optional<LightRandomization> lights;
  DrawPer lights_per = DrawPer::kFrame;
  std::optional<EnvironmentRandomization> environment;
  DrawPer environment_per = DrawPer::kFrame;
  std::optional<BackgroundRandomization> background;
  DrawPer background_per = DrawPer::kFrame;
  std::optional<CameraRandomization> camera;           // always per frame
  std::optional<DistractorRandomization> distractors;  // per scene (geometry)
  // Filled in by the run: the scene's first distractor among its fixtures (they are the last
  // ones), and what its distractors are (every frame's record repeats it).
  size_t first_distractor = 0;
  std::vector<Drawn> scene_record;

  // Anything the path tracer shades differently (materials, lights, environment, exposure and
  // white balance; distractors' own materials, but not the distractors; background photos): needs
  // render.mode pbr.
  bool changes_look() const;
  bool active() const { return changes_look() || camera.has_value() || distractors.has_value(); }
  bool Check(std::string* why) const;

  // Its own options: the seed (a run's: Reseed moves it; read by hand, a negative one wraps) and
  // how often each group is drawn (each its section's `per`). The groups describe theirs.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    Field seed = RunSeed("seed", "the draws' seed");
    seed.by_hand = true;
    visit(o.seed, seed);
    visit(o.floor_per, DrawPerField("", "floor_per"));
    visit(o.fixtures_per, DrawPerField("", "fixtures_per"));
    visit(o.lights_per, DrawPerField("", "lights_per"));
    visit(o.environment_per, DrawPerField("", "environment_per"));
    visit(o.background_per, DrawPerField("", "background_per"));
  }
};

// What one frame is drawn to be.
struct FrameDraw {
  FrameLook look;
  Eigen::Isometry3d world_from_cam = Eigen::Isometry3d::Identity();  // jittered
  SensorOptions sensor;
  std::vector<Drawn> record;
};

// Draws frame `view` of scene `scene`: `base` is the scene's own look (Renderer::BaseLook),
// `world_from_cam` and `sensor` the frame's camera as the sweep places it, `centre` the point
// (world, mm) lights are aimed at and placed about.
FrameDraw DrawFrame(const Randomization& r, const FrameLook& base,
                    const Eigen::Isometry3d& world_from_cam, const SensorOptions& sensor,
                    const Eigen::Vector3d& centre, uint64_t scene, uint64_t view);

// The distractors of scene `scene` (none unless r.distractors is set), picked from the objects
// named `names`, of which object i takes sizes[i] of the three sizes (a box 3, a cylinder 2, a
// sphere 1, a part 0), recorded in `record` as "distractor.count", "distractor.K.object", ".size"
// (the sizes it takes) and ".color". Drawn per scene, from streams randomize.draw.distractor.*.
std::vector<DistractorPick> DrawDistractors(const Randomization& r, uint64_t scene,
                                            const std::vector<std::string>& names,
                                            const std::vector<int>& sizes,
                                            std::vector<Drawn>* record);
// The seed of a scene's distractor drop (ArrangementOptions::distractor_seed).
uint64_t DistractorDropSeed(const Randomization& r, uint64_t scene);

// The colour of a black body at `kelvin` (1,667-25,000 K) as linear sRGB (Rec. 709 primaries,
// D65 white) scaled so that its largest component is 1: the Planckian locus in CIE xy by Kim et
// al.'s cubic fit (as Blender's Blackbody node), then XYZ with Y = 1 to linear sRGB.
Eigen::Vector3f BlackbodyColor(double kelvin);
// Gains on linear RGB (green gain 1) that turn light of `kelvin` into light of 6,504 K (D65's
// temperature; gains 1 there): a camera white-balanced for that colour temperature.
Eigen::Vector3f WhiteBalanceGains(double kelvin);

}  // namespace cadsynth
