#include "recipes/recipe.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include <yaml-cpp/yaml.h>

#include "cad/core/error.h"
#include "cad/core/schema.h"
#include "cad/core/util.h"
#include "dataset/output_formats.h"
#include "recipes/recipe_schema.h"
#include "recipes/sections.h"
#include "variants/families.h"

namespace cadsynth {
using namespace recipe_detail;  // the reader and its sections (recipes/reader.h, sections.h)

namespace {

// A density in kg/m3 that a solid part could have: from rigid foam (about 100) to osmium (22,590).
// 7.85 meant g/cm3 (steel); the message says what it was read as and what was likely meant.
void CheckDensity(const Reader& r, const YAML::Node& node, const std::string& key, double value) {
  if (value >= 100.0 && value <= 25000.0) return;
  std::ostringstream m;
  m << node.Scalar() << " is read as kg/m3, ";
  if (value < 100.0) {
    m << "lighter than any solid part (steel is 7850, aluminium 2700, ABS 1050)";
    if (value >= 0.1 && value <= 25.0)
      m << ": did you mean " << value * 1000.0 << " (" << node.Scalar() << " g/cm3)?";
  } else {
    m << "denser than any material (osmium is 22590)";
  }
  r.Fail(node, key, m.str());
}

// How a part or a container behaves in contact: density (kg/m3), friction, restitution; each a
// number or, where `ranges`, [low, high] drawn per scene.
void ReadPhysics(const Reader& r, const YAML::Node& node, const std::string& key, PhysicsDraw* d,
                 const Key& schema, bool ranges) {
  r.ExpectKeys(node, key, schema);
  // Each described field (PhysicsMaterial::Fields) into both ends, the high end's found by its
  // place among the fields.
  std::vector<double*> high;
  PhysicsMaterial::Fields(d->high,
                          [&high](double& value, const Field&) { high.push_back(&value); });
  size_t i = 0;
  PhysicsMaterial::Fields(d->low, [&](double& low, const Field& field) {
    double& hi = *high[i++];
    const YAML::Node v = node[std::string(field.key)];
    if (!v) return;
    const std::string at = key + "." + std::string(field.key);
    if (v.IsSequence()) {
      if (!ranges) r.Fail(v, at, "expected a number (a container's is not drawn)");
      if (v.size() != 2) r.Fail(v, at, "expected a number or a range [low, high]");
      ReadField(r, v[0], at, field, &low);
      ReadField(r, v[1], at, field, &hi);
      if (field.key == "density") {
        CheckDensity(r, v[0], at, low);
        CheckDensity(r, v[1], at, hi);
      }
      if (low > hi) r.Fail(v, at, "the range's low end exceeds its high end");
    } else {
      ReadField(r, v, at, field, &low);
      if (field.key == "density") CheckDensity(r, v, at, low);
      hi = low;
    }
  });
  r.Check(*d, node, key);
}

// A pile's container: {type: tote | floor | file, inner: [x, y], height, wall, floor,
// corner_radius (tote), file, unit, encoding, up (file), color, material, friction, restitution}.
void ReadContainer(const Reader& r, const YAML::Node& node, const std::string& key,
                   SceneSpec* scene) {
  Container& c = scene->arrangement.container;
  PhysicsDraw material(c.material);
  ReadPhysics(r, node, key, &material, SchemaAt("scene.container"), false);  // a mapping
  c.material = material.low;
  if (!node["type"]) r.Fail(node, key, "a container needs a 'type': tote, floor or file");
  // (A file's mesh is read with the parts: prepare.)
  c.kind = ReadKnown<Container::Kind>(r, node["type"], key + ".type", FieldOf<Container>("type"),
                                      "container");
  // (Keys of another type were refused by ReadPhysics' ExpectKeys: Key::only_with.)
  if (c.kind == Container::Kind::kMesh) {
    if (!node["file"]) r.Fail(node, key, "a container of type file needs a 'file' (CAD or mesh)");
    PartSource source;
    ReadUp(r, node, key, &source);
    ReadFileSource(r, node, key, &source);
    scene->container_file = std::move(source);
  }
  // A tote's inside below 10 mm holds no part: [0.4, 0.3] meant metres.
  for (const char* size : {"inner", "height"}) {
    if (node[size] && c.kind == Container::Kind::kTote)
      r.CheckMetresMeant(node[size], key + "." + size, 10.0);
  }
  if (const YAML::Node inner = node["inner"]) {
    if (!inner.IsSequence() || inner.size() != 2)
      r.Fail(inner, key + ".inner", "expected [length, width], e.g. [355 mm, 265 mm]");
    c.inner_mm = {r.Length(inner[0], key + ".inner"), r.Length(inner[1], key + ".inner")};
  }
  ReadDescribed(r, node, key, &c);
  if (node["color"]) scene->container_color = r.Color(node["color"], key + ".color");
  if (node["material"])
    scene->container_material =
        ReadMaterial(r, node["material"], key + ".material", SchemaAt("scene.container.material"));
  std::string why;
  if (!(c.kind == Container::Kind::kMesh ? c.material.Check(&why) : c.Check(&why)))
    r.FailAtNamedKey(node, key, why);
}

// A scene's arrangement keys (ArrangementOptions::Fields) and a pile's `container` and
// `physics`; `schema` is the section's (the root `scene`, or an entry of `scenes` with its own
// keys, read elsewhere).
void ReadLayout(const Reader& r, const YAML::Node& node, const std::string& key, SceneSpec* scene,
                const Key& schema) {
  if (node["radius"])
    r.CheckMetresMeant(node["radius"], key + ".radius", 10.0);  // the clutter disc
  ReadFields(r, node, key, &scene->arrangement, schema);
  scene->where = r.Where(node);
  if (node["container"]) scene->container_where = r.Where(node["container"]);
  if (node["copies"]) scene->copies_where = r.Where(node["copies"]);
  const bool pile = scene->arrangement.layout == Layout::kPile;
  const bool dropped = pile || scene->arrangement.pose == PoseMode::kDropped;
  if (node["container"] && !pile)
    r.Fail(node["container"], key + ".container", "only a pile (layout: pile) has one");
  if (node["physics"] && !dropped) {
    r.Fail(node["physics"], key + ".physics",
           "only a pile (layout: pile) or dropped parts (pose: dropped) have physics");
  }
  if (node["container"]) ReadContainer(r, node["container"], key + ".container", scene);
  if (const YAML::Node sequence = node["sequence"]) {
    if (!pile)
      r.Fail(sequence, key + ".sequence", "only a pile (layout: pile) has a pick sequence");
    ReadFields(r, sequence, key + ".sequence", &scene->arrangement.sequence,
               SchemaAt("scene.sequence"));
    r.Check(scene->arrangement.sequence, sequence, key + ".sequence");
  }
  if (const YAML::Node physics = node["physics"]; physics && physics.IsSequence()) {
    // Rules: the first whose patterns match a part gives its physics.
    for (size_t i = 0; i < physics.size(); ++i) {
      const std::string at = key + ".physics[" + std::to_string(i) + "]";
      PhysicsRule rule;
      rule.where = r.Where(physics[i]);
      rule.physics = scene->arrangement.physics;
      ReadPhysics(r, physics[i], at, &rule.physics, SchemaAt("scene.physics"), true);
      ReadPartPatterns(r, physics[i], at, &rule);
      scene->physics_rules.push_back(std::move(rule));
    }
  } else if (physics) {
    // One map for every part: rules (name, family, file) go in a list.
    for (const char* k : {"name", "family", "file"}) {
      if (physics.IsMap() && physics[k])
        r.Fail(physics[k], key + ".physics." + k,
               "a rule's pattern: give the rules as a list, [{" + std::string(k) + ": ..., ...}]");
    }
    ReadPhysics(r, physics, key + ".physics", &scene->arrangement.physics,
                SchemaAt("scene.physics"), true);
  }
  r.Check(scene->arrangement, node, key);
}

SceneSpec ReadSceneEntry(const Reader& r, const YAML::Node& node, const std::string& key) {
  r.ExpectKeys(node, key, SchemaAt("scenes[]"));
  if (!node["parts"]) r.Fail(node, key, "a scene needs 'parts'");
  SceneSpec scene;
  // (`randomize` is read once the recipe's own is known.)
  ReadLayout(r, node, key, &scene, SchemaAt("scenes[]"));
  scene.name = node["name"] ? r.Scalar(node["name"], key + ".name") : key;
  scene.sources = ReadParts(r, node["parts"], key + ".parts");
  return scene;
}

void ReadTessellation(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  ReadFields(r, node, "tessellation", &spec->tessellation, SchemaAt("tessellation"));
  if (node["crease_angle"]) {
    ReadField(r, node["crease_angle"], "tessellation.crease_angle",
              FieldOf<RunSpec>("crease_angle"), &spec->crease_angle_rad);
    if (spec->crease_angle_rad < 0.0 || spec->crease_angle_rad > M_PI) {
      r.Fail(node["crease_angle"], "tessellation.crease_angle",
             "must lie between 0 and 180 degrees");
    }
  }
  r.Check(spec->tessellation, node, "tessellation");
}

void ReadOutput(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  ReadFields(r, node, "output", &spec->bop, SchemaAt("output"));
  // Keys that depend on others.
  if (node["visibility_delta"]) {
    if (spec->bop.visibility != BopOptions::Visibility::kBop19) {
      r.Fail(node["visibility_delta"], "output.visibility_delta", "needs visibility: bop19");
    }
    spec->bop.visib_delta_mm = r.Length(node["visibility_delta"], "output.visibility_delta");
    if (!(spec->bop.visib_delta_mm >= 0))
      r.Fail(node["visibility_delta"], "output.visibility_delta", "must not be negative");
  }
  if (node["rgb"]) {
    const std::string kind = r.Scalar(node["rgb"], "output.rgb");
    if (kind != "png" && kind != "jpg" && kind != "jpeg") {
      r.Fail(node["rgb"], "output.rgb", "expected png or jpg, got '" + kind + "'");
    }
    spec->bop.jpeg_quality = kind == "png" ? 0 : 95;
  }
  if (node["jpeg_quality"]) {
    if (spec->bop.jpeg_quality == 0)
      r.Fail(node["jpeg_quality"], "output.jpeg_quality", "needs rgb: jpg");
    spec->bop.jpeg_quality = r.Integer(node["jpeg_quality"], "output.jpeg_quality");
    if (spec->bop.jpeg_quality < 1 || spec->bop.jpeg_quality > 100) {
      r.Fail(node["jpeg_quality"], "output.jpeg_quality", "expected 1 to 100");
    }
  }
  if (const YAML::Node formats = node["formats"]) {
    if (!formats.IsSequence())
      r.Fail(formats, "output.formats", "expected a list, e.g. [bop, coco, paper]");
    // Each format of dataset/output_formats.cpp is off unless listed.
    for (const OutputFormat& format : OutputFormats()) {
      if (format.enabled != nullptr) spec->bop.*format.enabled = false;
    }
    bool bop = false;
    for (const YAML::Node& f : formats) {
      const std::string name = r.Scalar(f, "output.formats");
      const OutputFormat* format = FindOutputFormat(name);
      if (format == nullptr) {
        r.Fail(f, "output.formats",
               "unknown format '" + name + "' (known: " + JoinNames(OutputFormatNames()) + ")");
      }
      if (format->enabled == nullptr) {
        bop = true;
      } else {
        spec->bop.*format->enabled = true;
      }
    }
    if (!bop)
      r.Fail(formats, "output.formats",
             "bop is always written (the other formats derive from it): list it");
  }
  if (node["test_every"] && node["test_fraction"]) {
    r.Fail(node["test_fraction"], "output.test_fraction",
           "give test_every or test_fraction, not both");
  }
  if (node["test_every"]) spec->bop.test_every = r.Integer(node["test_every"], "output.test_every");
  if (node["test_fraction"]) {
    spec->bop.test_every = 0;
    spec->bop.test_fraction = r.Number(node["test_fraction"], "output.test_fraction");
  }
  if (node["dir"]) {
    std::filesystem::path dir = r.Scalar(node["dir"], "output.dir");
    spec->output = (dir.is_relative() ? r.base_dir() / dir : dir).lexically_normal();
  }
  r.Check(spec->bop, node, "output");
}

}  // namespace

std::vector<SceneSpec> DemoScenes() {
  const auto family = [](const std::string& name, ParamValues values = {}) {
    PartSource source;
    source.kind = PartSource::Kind::kFamily;
    source.family = name;
    source.variants = {CompleteParams(*FindFamily(name), values)};
    return source;
  };
  SceneSpec planetary{"planetary_gearbox", {family("planetary")}, {.layout = Layout::kAssembled}};
  SceneSpec crank{"slider_crank", {family("slider_crank")}, {.layout = Layout::kAssembled}};
  SceneSpec benchmark{
      "assembly_benchmark",
      {family("round_peg"), family("square_peg"), family("faceplate"), family("stepped_shaft"),
       family("hex_bolt", {{"size", std::string("M10")}, {"length", 40.0}})},
      {.layout = Layout::kGrid, .gap_mm = 30.0}};
  return {planetary, crank, benchmark};
}

RunSpec Reseed(const RunSpec& spec, uint64_t stream) {
  RunSpec out = spec;
  if (stream == 0) return out;
  out.reseed = stream;
  // Each seed to a hash of itself and the stream (SplitMix64's finaliser), so that streams do
  // not collide with each other's seeds or with the recipe's.
  const auto move = [stream](uint64_t seed) {
    uint64_t z = seed ^ (stream * 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  };
  // Every described seed marked as a run's (Field::per_run_seed).
  const auto seeds = [&](auto& options) {
    std::decay_t<decltype(options)>::Fields(options, [&](auto& value, const Field& field) {
      using T = std::decay_t<decltype(value)>;
      if constexpr (std::is_same_v<T, int>) {  // a recipe's int (render.seed): kept non-negative
        if (field.per_run_seed) value = static_cast<int>(move(static_cast<uint64_t>(value)) >> 33);
      } else if constexpr (std::is_same_v<T, uint64_t>) {
        if (field.per_run_seed) value = move(value);
      }
    });
  };
  for (SceneSpec& scene : out.scenes) {
    seeds(scene.arrangement);
    if (scene.randomize) seeds(scene.randomize->draws);
  }
  seeds(out.randomize.draws);
  seeds(out.sampler);
  seeds(out.render);
  seeds(out.bop);
  seeds(out.tessellation);
  seeds(out.limits);
  const auto sensor_seeds = [&](SensorOptions& sensor) {
    seeds(sensor.imager);
    seeds(sensor.depth);
    seeds(sensor.lens);
  };
  sensor_seeds(out.sensor);
  for (RigSensor& sensor : out.rig) sensor_seeds(sensor.sensor);
  seeds(out.grasps.gripper);
  seeds(out.grasps.sampling);
  seeds(out.grasps.scene);
  seeds(out.grasps.labels);
  seeds(out.grasps.cup);
  seeds(out.grasps.suction_sampling);
  return out;
}

RunSpec DefaultRunSpec() {
  RunSpec spec;
  spec.scenes = DemoScenes();
  for (int yaw = 0; yaw < 360; yaw += 30) spec.sweep.yaw_rad.push_back(yaw * kDeg);
  for (int pitch = 15; pitch <= 75; pitch += 20) spec.sweep.pitch_rad.push_back(pitch * kDeg);
  spec.sweep.radius_mm = {650.0, 1050.0, 1450.0};
  return spec;
}

// yaml-cpp keeps every pair of a mapping but looks a key up by its first pair: a key (or a whole
// section) written twice would silently lose one of its values.
void RejectDuplicateKeys(const std::string& name, const YAML::Node& node) {
  const auto where = [&](const YAML::Mark& mark) {
    return name + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
  };
  if (node.IsMap()) {
    std::map<std::string, YAML::Mark> seen;
    for (auto it = node.begin(); it != node.end(); ++it) {
      if (it->first.IsScalar()) {
        const auto [first, fresh] = seen.emplace(it->first.Scalar(), it->first.Mark());
        if (!fresh) {
          throw Error(where(it->first.Mark()) + ": '" + it->first.Scalar() +
                      "' is given twice (first at line " + std::to_string(first->second.line + 1) +
                      ")");
        }
      }
      RejectDuplicateKeys(name, it->second);
    }
  } else if (node.IsSequence()) {
    for (const YAML::Node& child : node) RejectDuplicateKeys(name, child);
  }
}

namespace {

// `grasps:` (see GraspSpec).
GraspSpec ReadGrasps(const Reader& r, const YAML::Node& g) {
  r.ExpectKeys(g, "grasps", SchemaAt("grasps"));
  GraspSpec grasps;
  grasps.enabled = true;
  std::string why;
  if (const YAML::Node node = g["gripper"]) {
    const auto preset = [&](const YAML::Node& n, const std::string& key) {
      const std::string name = r.Scalar(n, key);
      if (name == "franka") return ParallelJawGripper::Franka();
      if (name == "robotiq_2f85") return ParallelJawGripper::Robotiq2F85();
      r.Fail(n, key, "unknown gripper '" + name + "' (known: franka, robotiq_2f85)");
    };
    if (node.IsMap()) {
      r.ExpectKeys(node, "grasps.gripper", SchemaAt("grasps.gripper"));
      if (node["preset"]) grasps.gripper = preset(node["preset"], "grasps.gripper.preset");
      ReadDescribed(r, node, "grasps.gripper", &grasps.gripper);
      if (!grasps.gripper.Check(&why)) r.Fail(node, "grasps.gripper", why);
    } else {
      grasps.gripper = preset(node, "grasps.gripper");
    }
  }
  AntipodalOptions& s = grasps.sampling;
  ReadDescribed(r, g, "grasps", &s);
  if (const YAML::Node depths = g["depths"]) {  // on the fingers of the gripper given
    if (!depths.IsSequence() || depths.size() == 0)
      r.Fail(depths, "grasps.depths", "expected a list of lengths");
    for (const YAML::Node& item : depths) {
      const double depth = r.Length(item, "grasps.depths");
      if (!(depth >= 0 && depth <= grasps.gripper.finger_length_mm)) {
        std::ostringstream what;
        what << "must lie on the fingers (0 to " << grasps.gripper.finger_length_mm << " mm)";
        r.Fail(item, "grasps.depths", what.str());
      }
      s.depths_mm.push_back(depth);
    }
  }
  if (!s.Check(&why)) r.Fail(g, "grasps", why);
  if (const YAML::Node node = g["suction"]) {
    if (node.IsScalar()) {
      grasps.suction = r.Bool(node, "grasps.suction");  // true: the default cup
    } else {
      grasps.suction = true;
      r.ExpectKeys(node, "grasps.suction", SchemaAt("grasps.suction"));
      ReadDescribed(r, node, "grasps.suction", &grasps.cup);
      if (!grasps.cup.Check(&why)) r.Fail(node, "grasps.suction", why);
      ReadDescribed(r, node, "grasps.suction", &grasps.suction_sampling);
      if (!grasps.suction_sampling.Check(&why)) r.Fail(node, "grasps.suction", why);
    }
  }
  grasps.suction_sampling.seed = s.seed;
  grasps.suction_sampling.max_grasps = s.max_grasps;
  ReadDescribed(r, g, "grasps", &grasps.scene);
  if (!grasps.scene.Check(&why)) r.Fail(g["approach_distance"], "grasps.approach_distance", why);
  GraspLabelOptions& labels = grasps.labels;
  ReadDescribed(r, g, "grasps", &labels);
  if (!labels.Check(&why)) {
    // At the key at fault: the count alone (with the default tolerance) passes or not.
    GraspLabelOptions count;
    count.max_per_instance = labels.max_per_instance;
    std::string count_why;
    const char* bad = count.Check(&count_why) ? "visibility_tolerance" : "per_instance";
    r.Fail(g[bad], std::string("grasps.") + bad, why);
  }
  labels.graspnet = true;
  labels.suctionnet = grasps.suction;
  if (const YAML::Node formats = g["formats"]) {
    if (!formats.IsSequence() || formats.size() == 0)
      r.Fail(formats, "grasps.formats", "expected a list of acronym, graspnet, suctionnet");
    grasps.acronym = labels.graspnet = labels.suctionnet = false;
    for (const YAML::Node& item : formats) {
      const std::string name = r.Scalar(item, "grasps.formats");
      if (name == "acronym") {
        grasps.acronym = true;
      } else if (name == "graspnet") {
        labels.graspnet = true;
      } else if (name == "suctionnet") {
        if (!grasps.suction)
          r.Fail(item, "grasps.formats", "suctionnet needs a cup (grasps.suction)");
        labels.suctionnet = true;
      } else {
        r.Fail(item, "grasps.formats",
               "unknown format '" + name + "' (known: acronym, graspnet, suctionnet)");
      }
    }
  }
  return grasps;
}

}  // namespace

RunSpec ParseRecipe(const std::string& text, const std::string& name,
                    const std::filesystem::path& base_dir) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw Error(name + ":" + std::to_string(e.mark.line + 1) + ":" +
                std::to_string(e.mark.column + 1) + ": not valid YAML: " + e.msg);
  }
  if (!root.IsMap()) throw Error(name + ": a recipe is a mapping of sections (parts, sweep, ...)");
  RejectDuplicateKeys(name, root);

  const Reader r(name, base_dir);
  RunSpec spec = DefaultRunSpec();
  try {
    r.ExpectKeys(root, "", RecipeSchema());
    if (root["scenes"] && (root["parts"] || root["scene"])) {
      r.Fail(root["scenes"], "scenes", "give either 'scenes' or 'parts' (with 'scene'), not both");
    }
    if (root["parts"]) {
      SceneSpec scene;
      scene.name = "scene";
      scene.sources = ReadParts(r, root["parts"], "parts");
      if (root["scene"]) {
        ReadLayout(r, root["scene"], "scene", &scene, SchemaAt("scene"));
      }
      spec.scenes = {scene};
    } else if (root["scene"]) {
      r.Fail(root["scene"], "scene",
             "'scene' goes with 'parts' (without parts the default scenes are used)");
    }
    if (root["scenes"]) {
      const YAML::Node scenes = root["scenes"];
      if (scenes.IsScalar() && scenes.Scalar() == "default") {
        spec.scenes = DemoScenes();
      } else {
        if (!scenes.IsSequence() || scenes.size() == 0)
          r.Fail(scenes, "scenes", "expected a list of scenes, or 'default'");
        spec.scenes.clear();
        for (size_t i = 0; i < scenes.size(); ++i) {
          spec.scenes.push_back(ReadSceneEntry(r, scenes[i], "scenes[" + std::to_string(i) + "]"));
        }
      }
    }
    if (root["classes"]) ReadClasses(r, root["classes"], &spec);
    if (root["tessellation"]) ReadTessellation(r, root["tessellation"], &spec);
    if (root["camera"] && root["cameras"]) {
      r.Fail(root["cameras"], "cameras",
             "give 'camera' (one camera) or 'cameras' (a rig of named cameras), not both");
    }
    if (root["camera"])
      ReadCamera(r, root["camera"], "camera", &spec.intrinsics, &spec.sensor, SchemaAt("camera"));
    if (root["cameras"]) ReadCameras(r, root["cameras"], &spec);
    if (root["sweep"]) ReadSweep(r, root["sweep"], &spec);
    if (root["render"]) ReadRender(r, root["render"], &spec);
    // The default floor material follows the floor colour unless the recipe gives one.
    spec.look.floor_material = Scene::DefaultFloorMaterial(spec.look.floor_color);
    if (root["materials"]) ReadMaterials(r, root["materials"], &spec);
    if (root["lighting"]) ReadLighting(r, root["lighting"], &spec);
    if (root["output"]) ReadOutput(r, root["output"], &spec);
    // The camera's image (a rig: the first camera's) decides the paper and pvn3d formats, which
    // are written for that camera only; every camera's image decides whether JPEG is possible.
    const YAML::Node first =
        root["cameras"] ? YAML::Node(root["cameras"][0]) : YAML::Node(root["camera"]);
    const std::string first_key = root["cameras"] ? "cameras[0]" : "camera";
    const auto image_node = [&](const YAML::Node& camera) {
      return camera && camera["image"] ? YAML::Node(camera["image"]) : camera;
    };
    if (spec.sensor.image != SensorOptions::Image::kRgb) {
      std::vector<std::string> rgb_only;
      for (const OutputFormat& format : OutputFormats()) {
        if (format.needs_rgb && format.enabled != nullptr) rgb_only.push_back(format.name);
      }
      for (const OutputFormat& format : OutputFormats()) {
        if (format.needs_rgb && format.enabled != nullptr && spec.bop.*format.enabled) {
          r.Fail(
              image_node(first), first_key + ".image",
              "the " + JoinNames(rgb_only, " and ") + " formats need colour images (image: rgb)");
        }
      }
    }
    spec.bop.gray_bits = GrayBits(spec.sensor.image);
    // Depth of field and motion blur come from the path tracer's samples; distorted IR images
    // cannot be matched by the stereo matcher, which wants them rectified.
    for (size_t i = 0; i < std::max<size_t>(1, spec.rig.size()); ++i) {
      const bool rig = !spec.rig.empty();
      const YAML::Node camera = rig ? YAML::Node(root["cameras"][i]) : YAML::Node(root["camera"]);
      const std::string at = rig ? "cameras[" + std::to_string(i) + "]" : std::string("camera");
      const SensorOptions& sensor = rig ? spec.rig[i].sensor : spec.sensor;
      const Intrinsics& k = rig ? spec.rig[i].intrinsics : spec.intrinsics;
      for (const char* effect : {"lens", "motion"}) {
        if (camera && camera[effect] && spec.render.mode != RenderOptions::Mode::kPbr) {
          r.Fail(camera[effect], at + "." + effect,
                 "depth of field and motion blur need render.mode: pbr (the path tracer's "
                 "samples)");
        }
      }
      if (k.distortion.active() && sensor.depth.kind == DepthModel::Kind::kActiveStereo) {
        r.Fail(camera["distortion"], at + ".distortion",
               "active_stereo matches rectified IR images: give the distortion to another camera "
               "of the rig");
      }
    }
    for (size_t i = 0; i < std::max<size_t>(1, spec.rig.size()); ++i) {
      const SensorOptions::Image image =
          spec.rig.empty() ? spec.sensor.image : spec.rig[i].sensor.image;
      if (image == SensorOptions::Image::kGray16 && spec.bop.jpeg_quality > 0) {
        const bool rig = !spec.rig.empty();
        r.Fail(image_node(rig ? YAML::Node(root["cameras"][i]) : YAML::Node(root["camera"])),
               (rig ? "cameras[" + std::to_string(i) + "]" : std::string("camera")) + ".image",
               "16-bit grey images cannot be JPEG (rgb: png)");
      }
    }
    if (root["randomize"]) {
      spec.randomize = ReadRandomize(r, root["randomize"], "randomize", RandomizeSpec{});
      CheckRandomize(r, root["randomize"], "randomize", spec.randomize, spec);
    }
    if (const YAML::Node scenes = root["scenes"]; scenes && scenes.IsSequence()) {
      for (size_t i = 0; i < scenes.size(); ++i) {
        const YAML::Node own = scenes[i]["randomize"];
        if (!own) continue;
        const std::string at = "scenes[" + std::to_string(i) + "].randomize";
        spec.scenes[i].randomize = ReadRandomize(r, own, at, spec.randomize);
        CheckRandomize(r, own, at, *spec.scenes[i].randomize, spec);
      }
    }
    if (const YAML::Node g = root["grasps"]) spec.grasps = ReadGrasps(r, g);
    if (root["collision"]) {
      ReadFields(r, root["collision"], "collision", &spec.collision, SchemaAt("collision"));
      r.Check(spec.collision, root["collision"], "collision");
    }
    if (root["limits"]) {
      ReadFields(r, root["limits"], "limits", &spec.limits, SchemaAt("limits"));
      r.Check(spec.limits, root["limits"], "limits");
    }
    CheckLimits(spec, name);
  } catch (const YAML::Exception& e) {
    throw Error(name + ":" + std::to_string(e.mark.line + 1) + ":" +
                std::to_string(e.mark.column + 1) + ": " + e.msg);
  }
  return spec;
}

int GrayBits(SensorOptions::Image image) {
  switch (image) {
    case SensorOptions::Image::kRgb:
      return 0;
    case SensorOptions::Image::kGray:
      return 8;
    case SensorOptions::Image::kGray16:
      return 16;
  }
  return 0;
}

std::vector<RigSensor> RunSensors(const RunSpec& spec) {
  if (!spec.rig.empty()) return spec.rig;
  RigSensor one;
  one.intrinsics = spec.intrinsics;
  one.sensor = spec.sensor;
  return {one};
}

bool RunLimits::Check(std::string* why) const {
  if (max_variants < 1 || max_count < 1) {
    *why = "max_variants and max_count must be at least 1";
  } else if (!(min_deflection_mm > 0) || !std::isfinite(min_deflection_mm)) {
    *why = "min_deflection must be a positive length";
  } else if (!(read_timeout_s > 0) || !std::isfinite(read_timeout_s)) {
    *why = "read_timeout must be a positive number of seconds";
  } else {
    return true;
  }
  return false;
}

void CheckLimits(const RunSpec& spec, const std::string& recipe) {
  const RunLimits& limits = spec.limits;
  size_t variants = 0;
  // The scenes' parts and the distractor sources the scenes use (an inherited one once).
  std::vector<const PartSource*> sources;
  std::set<std::string> counted;
  const auto distractors = [&](const RandomizeSpec& randomize) {
    if (!randomize.draws.distractors) return;
    for (const DistractorObject& object : randomize.distractor_objects) {
      if (object.kind != DistractorObject::Kind::kSource) continue;
      const std::string key = object.where + "|" + object.source.path.string() + "|" +
                              object.source.family + "|" +
                              std::to_string(object.source.variants.size());
      if (object.where.empty() || counted.insert(key).second) sources.push_back(&object.source);
    }
  };
  for (const SceneSpec& scene : spec.scenes) {
    for (const PartSource& source : scene.sources) sources.push_back(&source);
    distractors(scene.randomize ? *scene.randomize : spec.randomize);
  }
  {
    for (const PartSource* each : sources) {
      const PartSource& source = *each;
      const std::string where = source.where.empty() ? "" : source.where + ": ";
      variants += source.kind == PartSource::Kind::kFile ? 1 : source.variants.size();
      if (variants > static_cast<size_t>(limits.max_variants)) {
        throw Error(where + "the recipe asks for more than " + std::to_string(limits.max_variants) +
                    " parts and variants; if you mean it, raise limits.max_variants");
      }
      const FamilyInfo* family =
          source.kind == PartSource::Kind::kFamily ? FindFamily(source.family) : nullptr;
      if (family == nullptr) continue;
      for (const ParamValues& values : source.variants) {
        for (const FamilyParam& param : family->params) {
          if (param.kind != FamilyParam::Kind::kCount) continue;
          const auto it = values.find(param.name);
          if (it == values.end() || !std::holds_alternative<double>(it->second)) continue;
          const double count = std::get<double>(it->second);
          if (count > limits.max_count) {
            std::ostringstream out;
            out << where << source.family << ": " << param.name << " = " << count
                << " is more than " << limits.max_count
                << " (building it would take minutes); if you mean it, raise limits.max_count";
            throw Error(out.str());
          }
        }
      }
    }
  }
  if (spec.tessellation.linear_deflection_mm < limits.min_deflection_mm) {
    std::ostringstream out;
    out << (recipe.empty() ? "" : recipe + ": ") << "tessellation.linear_deflection "
        << spec.tessellation.linear_deflection_mm << " mm is finer than "
        << limits.min_deflection_mm
        << " mm (millions of triangles per part); if you mean it, lower limits.min_deflection";
    throw Error(out.str());
  }
}

RunSpec LoadRecipe(const std::filesystem::path& path) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) throw Error(path.string() + ": no such recipe file");
  if (std::filesystem::is_directory(status))
    throw Error(path.string() + ": is a folder, not a recipe");
  // A device or a pipe is read once and without end (/dev/zero): only regular files, bounded.
  if (!std::filesystem::is_regular_file(status))
    throw Error(path.string() + ": not a regular file (a recipe is a YAML file)");
  constexpr uintmax_t kMaxRecipeBytes = 16u << 20;
  const uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) throw Error(path.string() + ": cannot read the recipe: " + ec.message());
  if (size > kMaxRecipeBytes)
    throw Error(path.string() + ": " + std::to_string(size >> 20) +
                " MB is too large for a recipe (at most 16 MB)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string() + ": cannot open the recipe");
  std::string text(static_cast<size_t>(size), '\0');
  in.read(text.data(), static_cast<std::streamsize>(size));
  text.resize(static_cast<size_t>(in.gcount()));
  const std::filesystem::path base = std::filesystem::absolute(path, ec).parent_path();
  RunSpec spec = ParseRecipe(text, path.string(), base);
  spec.recipe = path;
  spec.recipe_text = std::move(text);
  return spec;
}

}  // namespace cadsynth
