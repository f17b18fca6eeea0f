#include "recipes/recipe_schema.h"

#include <algorithm>
#include <map>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "cad/shape.h"
#include "dataset/bop.h"
#include "dataset/grasp_labels.h"
#include "dataset/output_formats.h"
#include "recipes/recipe.h"
#include "render/camera.h"
#include "render/lights.h"
#include "render/material.h"
#include "render/randomize.h"
#include "render/renderer.h"
#include "render/scene.h"
#include "render/sensor.h"
#include "variants/arrangement.h"
#include "variants/families.h"
#include "variants/grasp/parallel_jaw.h"
#include "variants/grasp/scene_grasps.h"
#include "variants/grasp/suction.h"
#include "variants/physics/pile.h"

namespace cadsynth {
namespace {

// Builders that keep the tree below readable.
Key Value(std::string name, std::string kind, std::string doc, std::string default_text = {}) {
  Key key{std::move(name), std::move(kind), std::move(doc)};
  key.default_text = std::move(default_text);
  return key;
}
Key Choice(std::string name, std::vector<std::string> choices, std::string doc,
           std::string default_text = {}) {
  Key key = Value(std::move(name), "choice", std::move(doc), std::move(default_text));
  key.choices = std::move(choices);
  return key;
}
Key Section(std::string name, std::string doc, std::vector<Key> keys) {
  Key key{std::move(name), "section", std::move(doc)};
  key.keys = std::move(keys);
  return key;
}
Key List(std::string name, std::string doc, std::vector<Key> keys) {
  Key key = Section(std::move(name), std::move(doc), std::move(keys));
  key.kind = "list";
  return key;
}
Key Required(Key key) {
  key.required = true;
  return key;
}
Key OnlyWith(Key key, std::vector<std::string> tags) {
  key.only_with = std::move(tags);
  return key;
}
// `keys` followed by `more`.
std::vector<Key> Join(std::vector<Key> keys, const std::vector<Key>& more) {
  keys.insert(keys.end(), more.begin(), more.end());
  return keys;
}
// The key called `name` among `keys` (a described one, to add what only the tree knows).
Key& Named(std::vector<Key>& keys, std::string_view name) {
  for (Key& key : keys)
    if (key.name == name) return key;
  throw std::logic_error("recipe schema: no key '" + std::string(name) + "'");
}
// The described key `name` of `Options` alone (RunSpec's own options lie in several sections).
template <typename Options>
Key KeyOf(std::string_view name) {
  std::vector<Key> keys = KeysOf<Options>();
  return Named(keys, name);
}
// `keys` with `more` after the key called `name` (keys read by hand among described ones).
std::vector<Key> After(std::vector<Key> keys, std::string_view name, const std::vector<Key>& more) {
  const size_t at = &Named(keys, name) - keys.data();
  keys.insert(keys.begin() + at + 1, more.begin(), more.end());
  return keys;
}
// A section whose keys go with values of its key `tag` (Key::tag, Field::only_with); a required
// tag has no default, else its default is the tag's value when absent.
Key Tagged(Key section, std::string tag, bool required) {
  Key& key = Named(section.keys, tag);
  key.required = required;
  if (required) {
    key.default_text.clear();
  } else {
    section.tag_default = key.default_text;
  }
  section.tag = std::move(tag);
  return section;
}

std::vector<std::string> FamilyNames() {
  std::vector<std::string> names;
  for (const FamilyInfo& f : Families()) names.push_back(f.name);
  return names;
}

std::vector<std::string> CameraPresetNames() {
  std::vector<std::string> names;
  for (const CameraPreset& p : CameraPresets()) names.emplace_back(p.name);
  return names;
}

const std::vector<std::string> kAxes = {"x", "y", "z", "-x", "-y", "-z"};

// Which parts a rule is for: shell globs, case-insensitive, at least one.
std::vector<Key> PartPatterns() {
  return {Value("name", "text", "parts whose name matches this glob"),
          Value("family", "text", "parts the family of this name (or glob) built"),
          Value("file", "text", "parts read from files matching this glob")};
}

// A family's variants: params, grid or random, and whether the variants are one class.
std::vector<Key> FamilyKeys() {
  return {Choice("family", FamilyNames(), "a parametric family (docs/parts.md)"),
          Value("params", "any", "the family's parameters: {name: value}"),
          Value("grid", "any",
                "variants: {parameter: a value, a list or {from, to, step}}, every combination"),
          Section("random", "seeded random variants",
                  {Required(Value("count", "integer", "how many variants (1-100000)")),
                   Value("seed", "integer", "the draws' seed", "0"),
                   Required(Value("params", "any",
                                  "{parameter: {from, to} or [choices]}: what each draws"))})};
}

// An entry of `parts:` (a file or a family).
std::vector<Key> PartKeys() {
  Key symmetry =
      List("symmetry",
           "auto (find them), none, or a list measured on the mesh: [{axis: [0, 0, 1], order: 20}]",
           {Required(Value("axis", "vector3", "the axis to turn about, in the part's CAD frame")),
            Value("order", "integer", "n-fold (0: continuous)"),
            Value("continuous", "bool", "a continuous rotation (order 0)"),
            Value("through", "length3", "a point on the axis (default: the surface's centroid)")});
  symmetry.scalar_kind = "choice";
  symmetry.scalar_choices = {"auto", "none"};
  symmetry.default_text = "auto";
  return Join(
      {Value("file", "path", "a STEP, IGES, BREP or mesh file (relative to the recipe)"),
       Value("unit", "text", "the unit the file's numbers are in (mm, m, in, ...), not the file's"),
       Value("encoding", "text", "STEP: the code page of raw-byte names (e.g. cp1251)")},
      Join(FamilyKeys(),
           {Choice("class", {"variant", "family"},
                   "a family's variants: each its own class, or all one class", "variant"),
            Choice("up", kAxes, "the axis the designer drew as up, turned to +z", "z"), symmetry,
            Value("symmetry_tolerance", "length",
                  "a moved surface point lands this near the surface (default: automatic)")}));
}

// A material of the physically based mode: a preset and/or its parameters (PrincipledParams,
// Material), and a texture (Texture).
std::vector<Key> MaterialKeys() {
  std::vector<Key> surface = KeysOf<PrincipledParams>();
  Named(surface, "base_color").scalar_kind = "text";  // cad
  Key texture = Tagged(
      Section("texture", "a procedural or image texture (none: no texture)", KeysOf<Texture>()),
      "type", true);
  texture.scalar_kind = "choice";
  texture.scalar_choices = {"none"};
  return Join(Join({Choice("preset", MaterialPresetNames(), "a preset the other keys then change")},
                   surface),
              Join(KeysOf<Material>(), {texture}));
}

// Physics of parts in contact (PhysicsMaterial): each a number or, drawn per scene, a range
// [low, high].
std::vector<Key> PhysicsKeys() {
  std::vector<Key> keys = KeysOf<PhysicsMaterial>(ArrangementOptions{}.physics.low);
  for (Key& key : keys) key.kind = "number_range";
  return keys;
}

// The keys of a scene: its arrangement, a pile's container and the physics.
std::vector<Key> SceneKeys() {
  // The container's keys (Container), a file's (read as a part's), its look, and its physics
  // (PhysicsMaterial, a plastic tote's by default).
  const Key container = Tagged(
      Section(
          "container", "a pile's container",
          Join(Join(KeysOf<Container>(),
                    {OnlyWith(Value("file", "path", "the container's CAD or mesh file"), {"file"}),
                     OnlyWith(Value("unit", "text", "the file's unit"), {"file"}),
                     OnlyWith(Value("encoding", "text", "STEP: code page of raw-byte names"),
                              {"file"}),
                     OnlyWith(Choice("up", kAxes, "the file's up axis", "z"), {"file"}),
                     Value("color", "color", "its colour in the fast mode (sRGB [r, g, b])"),
                     Section("material", "its material in the pbr mode", MaterialKeys())}),
               KeysOf<PhysicsMaterial>(Container{}.material))),
      "type", true);
  Key physics = Section(
      "physics",
      "a pile's (or dropped parts') physics: one map for all parts, or a list of rules {name | "
      "family | file, density, friction, restitution}, the first match wins",
      Join(PhysicsKeys(), PartPatterns()));
  physics.scalar_kind = "list";  // (the rules' form)
  const Key sequence = Section(
      "sequence",
      "a pile's pick sequence: after the pile rests, parts are taken out one at a time and the "
      "pile settles again; each step is a scene of its own (NAME_pick_01, ...)",
      KeysOf<PickSequence>());
  return Join(KeysOf<ArrangementOptions>(), {container, physics, sequence});
}

// A camera's keys (`camera:`, or each entry of `cameras:`).
std::vector<Key> CameraKeys() {
  Key depth = Section("depth",
                      "the depth sensor: a model's name, or {model, and keys overriding the "
                      "model's published defaults} (docs/sensors.md)",
                      KeysOf<DepthModel>());
  depth.scalar_kind = "choice";
  depth.scalar_choices = depth.keys.front().choices;
  depth.default_text = "ideal";
  Key motion = Section("motion", "pbr: motion blur, the camera's velocities in its own frame",
                       KeysOf<CameraMotion>());
  Key& exposure = Named(motion.keys, "exposure_ms");
  exposure.required = true;
  exposure.default_text.clear();  // (no default: it must be given)
  // A preset, the intrinsics (Intrinsics), a field of view in place of K, and the sensor.
  return Join(
      Join({Choice("preset", CameraPresetNames(), "a camera's intrinsics (docs/sensors.md)",
                   "kinect_v1")},
           KeysOf<Intrinsics>()),
      {Value("hfov", "angle", "horizontal field of view instead of fx, fy, cx, cy"),
       KeysOf<SensorOptions>().front(),
       Section("imager", "the image sensor: shot and read noise, vignetting",
               KeysOf<ImageSensor>()),
       depth, Section("distortion", "OpenCV's lens distortion", KeysOf<Distortion>()),
       Section("lens", "pbr: depth of field through a thin lens", KeysOf<ThinLens>()), motion});
}

// A group's `per` (DrawPerField): how often it is drawn.
Key Per(std::string doc) {
  const Field field = DrawPerField("per");
  return Choice("per", {field.choices.begin(), field.choices.end()}, std::move(doc),
                DefaultText(DrawPer::kFrame, field));
}

// A material's randomisation (MaterialRandomization) without its group's `per`: presets, a texture
// folder (read by hand) and the distributions.
std::vector<Key> MaterialDrawFields() {
  std::vector<Key> keys = KeysOf<MaterialRandomization>();
  Named(keys, "preset").default_text.clear();  // none: the material's own
  return After(keys, "preset",
               {Section("textures", "an image from a folder, projected triplanarly",
                        {Required(Value("folder", "folder", "the images to pick from")),
                         Value("scale", "length", "the tile size")})});
}

// A material's randomisation (floor, fixtures, distractors) and how often it is drawn.
std::vector<Key> MaterialDrawKeys() {
  return Join(MaterialDrawFields(), {Per("how often it is drawn")});
}

std::vector<Key> RandomizeKeys() {
  Key objects =
      List("objects", "what distractors are: box, cylinder, sphere, {file}, {folder}, {family}",
           Join({Choice("primitive", {"box", "cylinder", "sphere"}, "a primitive"),
                 Value("file", "path", "a CAD or mesh file"),
                 Value("folder", "folder", "every CAD or mesh file of a folder"),
                 Value("unit", "text", "the files' unit")},
                FamilyKeys()));
  objects.scalar_kind = "choice";
  objects.scalar_choices = {"box", "cylinder", "sphere"};
  // A part rule: its patterns, `each`, the material's keys, then `per` (PartRandomization).
  std::vector<Key> part = KeysOf<PartRandomization>();
  const std::vector<Key> part_keys = Join(Join(PartPatterns(), {Named(part, "each")}),
                                          Join(MaterialDrawFields(), {Named(part, "per")}));
  std::vector<Key> lights = KeysOf<LightRandomization>();
  Named(lights, "type").choices.clear();  // (its doc lists them)
  // The groups' described keys (their `per` is Randomization's), and those of their own syntax:
  // the environment's image folder and the distractors' objects.
  return Join(
      KeysOf<Randomization>(),
      {List("parts", "parts' materials: the first rule matching a part draws it", part_keys),
       Section("floor", "the floor's material", MaterialDrawKeys()),
       Section("fixtures", "totes' and containers' materials", MaterialDrawKeys()),
       Section("lights", "light sources placed around the scene",
               Join(lights, {Per("how often they are drawn")})),
       Section("environment", "the world's light",
               Join(Join({Section("images", "a world image per draw",
                                  {Required(Value("folder", "folder", "equirectangular images"))})},
                         KeysOf<EnvironmentRandomization>()),
                    {Per("how often it is drawn")})),
       Section("camera", "the camera's settings and pose jitter, per frame",
               KeysOf<CameraRandomization>()),
       Section("distractors", "objects dropped among the parts, per scene, never labelled",
               Join(After(KeysOf<DistractorRandomization>(), "count", {objects}),
                    {Section("material", "their materials", MaterialDrawKeys())})),
       Section("background", "photos pasted where nothing is hit (render.floor: false)",
               {Required(Value("folder", "folder", "the photos to pick from")),
                Per("how often it is drawn")})});
}

std::vector<Key> GraspKeys() {
  Key gripper = Section(
      "gripper", "the parallel-jaw gripper: a preset, or a map of its sizes",
      Join({Choice("preset", {"franka", "robotiq_2f85"}, "the sizes to start from", "franka")},
           KeysOf<ParallelJawGripper>(ParallelJawGripper::Franka())));
  gripper.scalar_kind = "choice";
  gripper.scalar_choices = {"franka", "robotiq_2f85"};
  Key suction = Section("suction", "a suction cup (true: the default cup)",
                        Join(KeysOf<SuctionCup>(), KeysOf<SuctionOptions>()));
  suction.scalar_kind = "bool";
  Key formats = Value("formats", "choices",
                      "the grasp files written (default: acronym, graspnet, and suctionnet with a "
                      "cup)");
  formats.choices = {"acronym", "graspnet", "suctionnet"};
  return Join(Join(Join({gripper}, KeysOf<AntipodalOptions>()),
                   Join({suction}, KeysOf<SceneGraspOptions>())),
              Join(KeysOf<GraspLabelOptions>(), {formats}));
}

Key BuildSchema() {
  Key parts = List("parts", "the parts of the one scene: files and families", PartKeys());
  Key scenes =
      List("scenes", "several BOP scenes, each {name, parts, the scene keys, randomize}",
           Join({Value("name", "text", "the scene's name"),
                 List("parts", "the scene's parts", PartKeys()),
                 Section("randomize", "this scene's own randomisation groups", RandomizeKeys())},
                SceneKeys()));
  scenes.scalar_kind = "choice";
  scenes.scalar_choices = {"default"};
  Key rig = List("cameras", "a rig of named cameras moved together; the first is the rig's frame",
                 Join({Required(Value("name", "text", "lower-case letters and digits (rgb_NAME/)")),
                       Value("position", "length3", "in the rig's frame"),
                       Value("look_at", "length3", "the point it looks at, in the rig's frame"),
                       Value("rotation", "numbers", "rig_R_cam, 9 numbers row-major")},
                      CameraKeys()));
  // The fast mode's look (Scene) and lights (Scene::Light: a direction or a position, no default).
  std::vector<Key> fast_light = KeysOf<Scene::Light>();
  for (const char* name : {"direction", "position"}) Named(fast_light, name).default_text.clear();
  const std::vector<Key> look =
      After(KeysOf<Scene>(), "ambient",
            {List("lights", "fast mode: directional or point lights (Lambert)", fast_light)});
  // A light's keys and the environment's (LightSource, Environment), and those read by hand: a
  // target in place of a direction, the rect's size, the sun's strength in place of a power.
  std::vector<Key> light = KeysOf<LightSource>();
  Named(light, "power").default_text.clear();  // none: a light needs one
  light = After(
      light, "direction",
      {OnlyWith(Value("target", "length3", "the point it shines at"), {"spot", "rect", "disc"})});
  light = After(light, "spot_blend",
                {OnlyWith(Value("size", "length_or_pair", "a length, or [x, y]",
                                DefaultText(LightSource{}.size_x_mm, Field{.kind = "length"})),
                          {"rect"})});
  light = After(light, "x_axis",
                {OnlyWith(Value("strength", "number", "irradiance, W/m2, as Blender's"), {"sun"})});
  const Key sources = Tagged(List("lights", "light sources, Blender's units", light), "type", true);
  const Key environment =
      Tagged(Section("environment", "the world's light", KeysOf<Environment>()), "type", false);
  Key output_formats = Value("formats", "choices", "bop (always) plus any of the others");
  output_formats.choices = OutputFormatNames();
  Key classes =
      Section("classes", "what one object class is",
              {KeyOf<RunSpec>("by"),
               Value("groups", "any", "{class name: a name glob or a list of globs}, in order")});

  Key root = Section(
      "", "a cadsynth recipe",
      {parts, Section("scene", "how the parts of `parts` lie on the floor", SceneKeys()), scenes,
       classes,
       Section("tessellation", "how B-rep surfaces become triangles",
               Join(KeysOf<TessellationOptions>(), {KeyOf<RunSpec>("crease_angle")})),
       Section("camera", "the one camera", CameraKeys()), rig,
       Section("sweep", "the camera views: each axis a value, a list or {from, to, step}",
               Join(Join(KeysOf<SweepOptions>(DefaultRunSpec().sweep), KeysOf<ViewSampler>()),
                    {KeyOf<RunSpec>("min_visible_pixels")})),
       Section("render", "ray casting and shading",
               Join(Join(KeysOf<RenderOptions>(), look), {KeyOf<RunSpec>("colors")})),
       Section("materials", "pbr: the materials of the floor and the parts",
               {Section("floor", "the floor's material", MaterialKeys()),
                Section("default", "parts no rule matches", MaterialKeys()),
                List("assign", "rules: the first whose patterns match a part gives its material",
                     Join(PartPatterns(), MaterialKeys()))}),
       Section("lighting", "pbr: light sources and the world", {sources, environment}),
       Section("randomize", "domain randomisation (docs/rendering.md)", RandomizeKeys()),
       Section("grasps", "grasp labels per object and per frame", GraspKeys()),
       Section("collision",
               "piles and drops: each part's collision shape (its hull, or convex pieces)",
               KeysOf<CollisionOptions>()),
       Section("output", "the dataset's layout and formats",
               Join(KeysOf<BopOptions>(),
                    {Value("dir", "text", "the output folder (-o wins)"), output_formats,
                     Choice("rgb", {"png", "jpg", "jpeg"}, "the colour images' format", "png")})),
       Section("limits", "how much work a recipe may ask for (raise them if you mean it)",
               KeysOf<RunLimits>())});
  return root;
}

// --- The reference --------------------------------------------------------------------------

std::string KindText(const Key& key) {
  std::string text = key.kind;
  if (!key.choices.empty()) {
    text += " (";
    for (size_t i = 0; i < key.choices.size(); ++i) text += (i ? " | " : "") + key.choices[i];
    text += ")";
  }
  if (!key.scalar_kind.empty() && key.scalar_kind != "list") {
    text += ", or " + key.scalar_kind;
    if (!key.scalar_choices.empty()) {
      text += " (";
      for (size_t i = 0; i < key.scalar_choices.size(); ++i)
        text += (i ? " | " : "") + key.scalar_choices[i];
      text += ")";
    }
  }
  return text;
}

void WriteReference(std::ostringstream& out, const Key& key, int depth) {
  const std::string indent(2 * depth, ' ');
  std::string line = indent + key.name + ":";
  if (key.kind != "section" && key.kind != "list" && !key.default_text.empty())
    line += " " + key.default_text;
  line.resize(std::max<size_t>(line.size() + 1, 36), ' ');
  std::string note = KindText(key);
  if (key.required) note += ", required";
  if (!key.only_with.empty()) {
    std::string with;
    for (const std::string& t : key.only_with) with += (with.empty() ? "" : " | ") + t;
    note += " (" + with + " only)";
  }
  out << line << "# " << note << ": " << key.doc << "\n";
  for (const Key& child : key.keys)
    WriteReference(out, child, depth + (key.kind == "list" ? 2 : 1));
}

// --- The JSON Schema -------------------------------------------------------------------------

using Json = nlohmann::ordered_json;

Json NumberOrText() { return Json{{"type", Json::array({"number", "string"})}}; }

Json Triple(const Json& item) {
  return Json{{"type", "array"}, {"items", item}, {"minItems", 3}, {"maxItems", 3}};
}

// A value of `kind` (not a section or list).
Json ValueSchema(const std::string& kind, const std::vector<std::string>& choices) {
  const Json number = Json{{"type", "number"}};
  const Json length = NumberOrText();  // 30, "30 mm", "0.5 m"
  const Json hex = Json{{"type", "string"}, {"pattern", "^#[0-9a-fA-F]{6}$"}};
  if (kind == "length" || kind == "angle") return length;
  if (kind == "number" || kind == "milliseconds") return number;
  if (kind == "integer") return Json{{"type", "integer"}};
  if (kind == "bool") return Json{{"type", "boolean"}};
  if (kind == "text" || kind == "path" || kind == "folder") return Json{{"type", "string"}};
  if (kind == "choice") {
    Json e = Json::array();
    for (const std::string& c : choices) {
      // A YAML loader reads `true`, `false` and numbers as such: accept them as the names.
      e.push_back(c);
      if (c == "true" || c == "false") e.push_back(c == "true");
    }
    return Json{{"enum", e}};
  }
  if (kind == "choices") return Json{{"type", "array"}, {"items", ValueSchema("choice", choices)}};
  if (kind == "color") return Triple(number);
  if (kind == "linear_color") return Json{{"anyOf", Json::array({Triple(number), hex})}};
  if (kind == "vector3" || kind == "degrees3") return Triple(number);
  if (kind == "length3") return Triple(length);
  if (kind == "lengths") return Json{{"type", "array"}, {"items", length}};
  if (kind == "numbers") return Json{{"type", "array"}, {"items", number}};
  if (kind == "length_or_pair") {
    return Json{{"anyOf", Json::array({length, Json{{"type", "array"},
                                                    {"items", length},
                                                    {"minItems", 2},
                                                    {"maxItems", 2}}})}};
  }
  if (kind == "number_range") {
    return Json{{"anyOf", Json::array({number, Json{{"type", "array"},
                                                    {"items", number},
                                                    {"minItems", 2},
                                                    {"maxItems", 2}}})}};
  }
  if (kind == "series_angle" || kind == "series_length") {
    Json range = {{"type", "object"},
                  {"properties", {{"from", length}, {"to", length}, {"step", length}}},
                  {"required", Json::array({"from", "to", "step"})},
                  {"additionalProperties", false}};
    return Json{
        {"anyOf", Json::array({length, Json{{"type", "array"}, {"items", length}}, range})}};
  }
  if (kind == "distribution" || kind == "distribution_length") {
    Json anyOf = Json::array({length});
    for (const char* d : {"uniform", "normal", "log_uniform", "choice"}) {
      Json list = {{"type", "array"}, {"items", length}};
      if (std::string(d) != "choice") list["minItems"] = list["maxItems"] = 2;
      anyOf.push_back(Json{{"type", "object"},
                           {"properties", {{d, list}}},
                           {"required", Json::array({d})},
                           {"additionalProperties", false}});
    }
    return Json{{"anyOf", anyOf}};
  }
  if (kind == "names") {
    const Json text = {{"type", "string"}};
    return Json{
        {"anyOf",
         Json::array({text, Json{{"type", "array"}, {"items", text}},
                      Json{{"type", "object"},
                           {"properties", {{"choice", {{"type", "array"}, {"items", text}}}}},
                           {"required", Json::array({"choice"})},
                           {"additionalProperties", false}}})}};
  }
  if (kind == "any") return Json::object();
  throw std::logic_error("recipe schema: no JSON Schema for kind '" + kind + "'");
}

Json KeySchema(const Key& key);

// A section's mapping: its keys, none other, the required ones, and the tag's rules.
Json SectionSchema(const Key& key) {
  Json properties = Json::object();
  Json required = Json::array();
  for (const Key& child : key.keys) {
    properties[child.name] = KeySchema(child);
    if (child.required) required.push_back(child.name);
  }
  Json schema = {{"type", "object"}, {"properties", properties}, {"additionalProperties", false}};
  if (!required.empty()) schema["required"] = required;
  if (!key.tag.empty()) {
    // Each tag value: the keys that do not go with it are absent.
    const Key* tag = key.Find(key.tag);
    Json rules = Json::array();
    for (const std::string& value : tag->choices) {
      Json absent = Json::array();
      for (const Key& child : key.keys) {
        if (child.only_with.empty()) continue;
        if (std::find(child.only_with.begin(), child.only_with.end(), value) !=
            child.only_with.end())
          continue;
        absent.push_back(Json{{"required", Json::array({child.name})}});
      }
      if (absent.empty()) continue;
      Json condition = {{"properties", {{key.tag, {{"const", value}}}}}};
      if (value == key.tag_default) {
        condition =
            Json{{"anyOf",
                  Json::array({condition, Json{{"not", {{"required", Json::array({key.tag})}}}}})}};
      } else {
        condition["required"] = Json::array({key.tag});
      }
      rules.push_back(Json{{"if", condition}, {"then", {{"not", {{"anyOf", absent}}}}}});
    }
    if (!rules.empty()) schema["allOf"] = rules;
  }
  return schema;
}

Json KeySchema(const Key& key) {
  Json schema;
  if (key.kind == "section") {
    schema = SectionSchema(key);
  } else if (key.kind == "list") {
    schema = Json{{"type", "array"}, {"items", SectionSchema(key)}};
  } else {
    schema = ValueSchema(key.kind, key.choices);
  }
  if (!key.scalar_kind.empty()) {
    Json other;
    if (key.scalar_kind == "list") {
      other = Json{{"type", "array"}, {"items", SectionSchema(key)}};
    } else if (key.kind == "list") {
      // A list whose items may be single values (objects: [box, {file: a.stl}]), or the list
      // written as one value (symmetry: auto).
      const Json one = ValueSchema(key.scalar_kind, key.scalar_choices);
      schema["items"] = Json{{"anyOf", Json::array({schema["items"], one})}};
      other = one;
    } else {
      other = ValueSchema(key.scalar_kind, key.scalar_choices);
    }
    schema = Json{{"anyOf", Json::array({schema, other})}};
  }
  schema["description"] =
      key.doc + (key.default_text.empty() ? "" : " (default: " + key.default_text + ")");
  return schema;
}

// Sections written more than once (a material in five places, a camera in two) once, in $defs,
// each use a $ref to it: the schema stays small enough to read and to ship.
// A section's schema as text, without its description (the same section is described per use).
std::string SectionText(const Json& node) {
  Json bare = node;
  bare.erase("description");
  return bare.dump();
}

void CountSections(const Json& node, std::map<std::string, int>* counts) {
  if (node.is_object()) {
    if (node.contains("properties") && node.value("type", "") == "object")
      ++(*counts)[SectionText(node)];
    for (const auto& item : node.items()) CountSections(item.value(), counts);
  } else if (node.is_array()) {
    for (const Json& item : node) CountSections(item, counts);
  }
}

void ShareSections(Json* node, const std::string& name, const std::map<std::string, int>& counts,
                   Json* defs, std::map<std::string, std::string>* names) {
  if (node->is_object()) {
    if (node->contains("properties") && node->value("type", "") == "object") {
      const std::string text = SectionText(*node);
      if (counts.at(text) > 1) {
        auto [it, added] = names->emplace(text, name);
        if (added) {
          // A name of its own: the key it was first seen under, numbered if taken.
          for (int n = 2; defs->contains(it->second); ++n) it->second = name + std::to_string(n);
          Json shared = *node;
          shared.erase("description");
          (*defs)[it->second] = Json::object();
          for (auto& item : shared["properties"].items())
            ShareSections(&item.value(), item.key(), counts, defs, names);
          (*defs)[it->second] = shared;
        }
        Json ref = {{"$ref", "#/$defs/" + it->second}};
        if (node->contains("description")) ref["description"] = (*node)["description"];
        *node = ref;
        return;
      }
    }
    for (auto& item : node->items()) {
      const bool key = node->contains("properties") && item.key() == "properties";
      if (key) {
        for (auto& property : item.value().items())
          ShareSections(&property.value(), property.key(), counts, defs, names);
      } else {
        ShareSections(&item.value(), name, counts, defs, names);
      }
    }
  } else if (node->is_array()) {
    for (Json& item : *node) ShareSections(&item, name, counts, defs, names);
  }
}

}  // namespace

const Key& RecipeSchema() {
  static const Key root = BuildSchema();
  return root;
}

const Key& SchemaAt(std::string_view path) {
  const Key* key = &RecipeSchema();
  std::string_view rest = path;
  while (!rest.empty()) {
    const size_t dot = rest.find('.');
    std::string_view part = rest.substr(0, dot);
    rest = dot == std::string_view::npos ? std::string_view() : rest.substr(dot + 1);
    if (part.size() > 2 && part.substr(part.size() - 2) == "[]") part.remove_suffix(2);
    key = key->Find(part);
    if (key == nullptr)
      throw std::logic_error("recipe schema: no section '" + std::string(path) + "'");
  }
  return *key;
}

std::string RecipeReference() {
  std::ostringstream out;
  out << "# Every recipe key, section by section: its default, kind and meaning. Lengths take a "
         "unit\n"
         "# (mm, cm, m, in; a bare number is mm), angles are degrees (or take rad). A list's "
         "items are\n"
         "# shown under it. docs/recipes.md has examples.\n";
  for (const Key& section : RecipeSchema().keys) WriteReference(out, section, 0);
  return out.str();
}

std::string RecipeJsonSchema() {
  Json schema = SectionSchema(RecipeSchema());
  std::map<std::string, int> counts;
  CountSections(schema, &counts);
  Json defs = Json::object();
  std::map<std::string, std::string> names;
  for (auto& item : schema["properties"].items())
    ShareSections(&item.value(), item.key(), counts, &defs, &names);
  Json root = {{"$schema", "https://json-schema.org/draft/2020-12/schema"},
               {"title", "cadsynth recipe"},
               {"description",
                "A cadsynth recipe (cadsynth generate RECIPE.yaml); written by cadsynth generate "
                "--recipe-schema from the same description the reader uses."}};
  root.update(schema);
  if (!defs.empty()) root["$defs"] = defs;
  return root.dump(2) + "\n";
}

}  // namespace cadsynth
