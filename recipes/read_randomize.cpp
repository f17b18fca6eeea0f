// Domain randomisation (`randomize:`), per recipe and per scene: groups, image folders,
// distractor objects, and the checks against the rest of the recipe.
#include "recipes/sections.h"

#include <algorithm>
#include <set>

#include "cad/core/units.h"

namespace cadsynth::recipe_detail {

namespace {

// A list of names, or one name, or {choice: [names]}: what is picked from, equally likely.
std::vector<std::pair<YAML::Node, std::string>> ReadNameChoice(const Reader& r,
                                                               const YAML::Node& node,
                                                               const std::string& key) {
  std::vector<std::pair<YAML::Node, std::string>> names;
  YAML::Node list = node;
  if (node.IsMap()) {
    r.ExpectMap(node, key, {"choice"});
    list = node["choice"];
  }
  if (list.IsScalar()) {
    names.emplace_back(list, r.Scalar(list, key));
  } else if (list.IsSequence() && list.size() > 0) {
    for (const YAML::Node& n : list) names.emplace_back(n, r.Scalar(n, key));
  } else {
    r.Fail(node, key, "expected a name, or {choice: [names]} (not empty)");
  }
  return names;
}

// Every PNG, JPEG, EXR and HDR image in the folder `node` names (relative to the recipe), sorted
// by name so that picks do not depend on the file system, read once.
ImageChoice ReadImageFolder(const Reader& r, const YAML::Node& node, const std::string& key) {
  std::filesystem::path folder = r.Scalar(node, key);
  if (folder.is_relative()) folder = r.base_dir() / folder;
  folder = folder.lexically_normal();
  std::error_code ec;
  if (!std::filesystem::is_directory(folder, ec))
    r.Fail(node, key, folder.string() + ": no such folder");
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (entry.is_regular_file() &&
        (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".exr" || ext == ".hdr")) {
      files.push_back(entry.path());
    }
  }
  if (files.empty())
    r.Fail(node, key, folder.string() + ": no PNG, JPEG, EXR or HDR images in the folder");
  std::sort(files.begin(), files.end());
  ImageChoice images;
  for (const std::filesystem::path& file : files) {
    try {
      images.pixels.push_back(LoadLinearImage(file));
    } catch (const Error& e) {
      r.Fail(node, key, e.what());
    }
    images.files.push_back(file);
    images.names.push_back(file.filename().string());
  }
  return images;
}

// A material's randomisation (parts, floor, fixtures, distractors): presets picked by name,
// textures from a folder, the described distributions, and its group's `per` (`per_field`).
MaterialRandomization ReadMaterialRandomization(const Reader& r, const YAML::Node& node,
                                                const std::string& key, const Key& schema,
                                                const Field& per_field, DrawPer* per) {
  r.ExpectKeys(node, key, schema);
  MaterialRandomization m;
  if (const YAML::Node p = node["preset"]) {
    for (const auto& [n, name] : ReadNameChoice(r, p, key + ".preset")) {
      Material preset;
      if (!MaterialPreset(name, &preset)) {
        const std::string best = NearestName(name, MaterialPresetNames());
        r.Fail(n, key + ".preset",
               "unknown material '" + name + "'" +
                   (best.empty() ? "" : " (did you mean '" + best + "'?)"));
      }
      m.presets.push_back(preset);
      m.preset_names.push_back(name);
    }
  }
  if (const YAML::Node t = node["textures"]) {
    // Every image in a folder, projected triplanarly in tiles of `scale` (meshes with texture
    // coordinates use them).
    const std::string at = key + ".textures";
    r.ExpectKeys(t, at, SchemaAt("randomize.floor.textures"));
    if (!t["folder"]) r.Fail(t, at, "give the 'folder' of images to pick from");
    const ImageChoice images = ReadImageFolder(r, t["folder"], at + ".folder");
    Texture texture;
    texture.kind = Texture::Kind::kImage;
    texture.scale_mm = 200.0;
    if (t["scale"])
      ReadField(r, t["scale"], at + ".scale", FieldOf<Texture>("scale"), &texture.scale_mm);
    for (size_t i = 0; i < images.files.size(); ++i) {
      texture.image = images.files[i];
      texture.pixels = images.pixels[i];
      m.textures.push_back(texture);
      m.texture_names.push_back(images.names[i]);
    }
  }
  ReadDescribed(r, node, key, &m);
  if (node["per"]) ReadField(r, node["per"], key + ".per", per_field, per);
  std::string why;
  if (!m.Check(&why)) r.Fail(node, key, why);
  return m;
}

// `randomize.distractors:`: how many, what (primitives, files, folders, families), how large, and
// their materials.
void ReadDistractors(const Reader& r, const YAML::Node& n, const std::string& at,
                     RandomizeSpec* spec) {
  r.ExpectKeys(n, at, SchemaAt("randomize.distractors"));
  DistractorRandomization d;
  ReadDescribed(r, n, at, &d);
  if (n["material"]) {
    d.material = ReadMaterialRandomization(
        r, n["material"], at + ".material", SchemaAt("randomize.distractors.material"),
        FieldOf<DistractorRandomization>("material_per"), &d.material_per);
  }
  std::vector<DistractorObject> objects;
  if (const YAML::Node list = n["objects"]) {
    if (!list.IsSequence() || list.size() == 0) {
      r.Fail(list, at + ".objects",
             "expected a list such as [box, cylinder, {file: part.stl}, {folder: clutter/}, "
             "{family: hex_nut}]");
    }
    static const std::vector<std::pair<std::string, DistractorObject::Kind>> primitives = {
        {"box", DistractorObject::Kind::kBox},
        {"cylinder", DistractorObject::Kind::kCylinder},
        {"sphere", DistractorObject::Kind::kSphere}};
    for (size_t i = 0; i < list.size(); ++i) {
      const YAML::Node item = list[i];
      const std::string key = at + ".objects[" + std::to_string(i) + "]";
      DistractorObject object;
      object.where = r.Where(item);
      if (item.IsScalar() || item["primitive"]) {
        const YAML::Node name_node = item.IsScalar() ? item : item["primitive"];
        if (!item.IsScalar()) {
          r.ExpectKeys(item, key, SchemaAt("randomize.distractors.objects[]"));
          if (item.size() > 1)
            r.Fail(item, key, "a primitive is all a distractor object then says: no other keys");
        }
        const std::string name = r.Scalar(name_node, key);
        const auto it = std::find_if(primitives.begin(), primitives.end(),
                                     [&](const auto& p) { return p.first == name; });
        if (it == primitives.end()) {
          r.Fail(name_node, key,
                 "unknown primitive '" + name +
                     "' (known: box, cylinder, sphere; files and families go in a map such as "
                     "{file: part.stl})");
        }
        object.kind = it->second;
        objects.push_back(std::move(object));
        continue;
      }
      r.ExpectKeys(item, key, SchemaAt("randomize.distractors.objects[]"));
      if ((item["file"] ? 1 : 0) + (item["folder"] ? 1 : 0) + (item["family"] ? 1 : 0) != 1)
        r.Fail(item, key, "give one of 'primitive', 'file', 'folder' or 'family'");
      object.kind = DistractorObject::Kind::kSource;  // (no `up`: distractors fall at random)
      if (item["family"]) {
        if (item["unit"]) r.Fail(item["unit"], key + ".unit", "goes with 'file' or 'folder'");
        ReadFamily(r, item, key, &object.source);
        objects.push_back(std::move(object));
        continue;
      }
      for (const char* k : {"params", "grid", "random"}) {
        if (item[k]) r.Fail(item[k], key + "." + k, "goes with 'family'");
      }
      if (item["file"]) {
        ReadFileSource(r, item, key, &object.source);
        objects.push_back(std::move(object));
        continue;
      }
      // A folder: every CAD and mesh file in it, sorted by name (the picks do not depend on the
      // file system's order).
      std::filesystem::path folder = r.Scalar(item["folder"], key + ".folder");
      if (folder.is_relative()) folder = r.base_dir() / folder;
      folder = folder.lexically_normal();
      std::error_code ec;
      if (!std::filesystem::is_directory(folder, ec))
        r.Fail(item["folder"], key + ".folder", folder.string() + ": no such folder");
      static const std::set<std::string> extensions = {".step", ".stp",  ".p21", ".iges", ".igs",
                                                       ".brep", ".rle",  ".stl", ".obj",  ".ply",
                                                       ".dae",  ".gltf", ".glb", ".3mf",  ".off"};
      std::vector<std::filesystem::path> files;
      for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
        std::string ext = entry.path().extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(),
                       [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        if (entry.is_regular_file() && extensions.count(ext) != 0) files.push_back(entry.path());
      }
      if (files.empty()) {
        r.Fail(item["folder"], key + ".folder",
               folder.string() +
                   ": no CAD or mesh files in the folder (STEP, IGES, BREP, STL, "
                   "OBJ, PLY, DAE, glTF, 3MF, OFF)");
      }
      std::sort(files.begin(), files.end());
      PartSource base = object.source;
      if (item["unit"]) {
        base.unit = r.Scalar(item["unit"], key + ".unit");
        if (!LengthUnitMm(base.unit)) {
          r.Fail(item["unit"], key + ".unit",
                 "unknown length unit '" + base.unit + "' (use um, mm, cm, m, in or ft)");
        }
      }
      for (const std::filesystem::path& file : files) {
        DistractorObject one = object;
        one.source = base;
        one.source.kind = PartSource::Kind::kFile;
        one.source.path = file;
        one.source.where = r.Where(item["folder"]);
        objects.push_back(std::move(one));
      }
    }
  } else {
    for (const auto kind : {DistractorObject::Kind::kBox, DistractorObject::Kind::kCylinder,
                            DistractorObject::Kind::kSphere}) {
      DistractorObject object;
      object.kind = kind;
      object.where = r.Where(n);
      objects.push_back(std::move(object));
    }
  }
  std::string why;
  if (!d.Check(&why)) r.Fail(n, at, why);
  spec->draws.distractors = std::move(d);
  spec->distractor_objects = std::move(objects);
}

}  // namespace

// `randomize:` (or a scene's, which replaces the groups it gives of `base`).
RandomizeSpec ReadRandomize(const Reader& r, const YAML::Node& node, const std::string& key,
                            const RandomizeSpec& base) {
  r.ExpectKeys(node, key, SchemaAt("randomize"));
  RandomizeSpec spec = base;
  Randomization& d = spec.draws;
  // (A negative seed wraps.)
  if (node["seed"]) d.seed = static_cast<uint64_t>(r.Integer(node["seed"], key + ".seed"));
  if (const YAML::Node parts = node["parts"]) {
    if (!parts.IsSequence())
      r.Fail(parts, key + ".parts", "expected a list of {name|family|file: pattern, ...}");
    d.parts.clear();
    spec.part_rules.clear();
    for (size_t i = 0; i < parts.size(); ++i) {
      const std::string at = key + ".parts[" + std::to_string(i) + "]";
      const YAML::Node item = parts[i];
      PartRandomization p;
      p.where = r.Where(item);
      p.material = ReadMaterialRandomization(r, item, at, SchemaAt("randomize.parts[]"),
                                             FieldOf<PartRandomization>("per"), &p.per);
      if (item["each"])
        ReadField(r, item["each"], at + ".each", FieldOf<PartRandomization>("each"),
                  &p.per_instance);
      RandomizeRule rule;
      rule.where = p.where;
      ReadPartPatterns(r, item, at, &rule);
      d.parts.push_back(std::move(p));
      spec.part_rules.push_back(std::move(rule));
    }
  }
  if (node["floor"]) {
    d.floor =
        ReadMaterialRandomization(r, node["floor"], key + ".floor", SchemaAt("randomize.floor"),
                                  FieldOf<Randomization>("floor_per"), &d.floor_per);
  }
  if (node["fixtures"]) {
    d.fixtures = ReadMaterialRandomization(r, node["fixtures"], key + ".fixtures",
                                           SchemaAt("randomize.fixtures"),
                                           FieldOf<Randomization>("fixtures_per"), &d.fixtures_per);
  }
  if (const YAML::Node n = node["lights"]) {
    const std::string at = key + ".lights";
    r.ExpectKeys(n, at, SchemaAt("randomize.lights"));
    LightRandomization l;
    ReadDescribed(r, n, at, &l);
    if (n["type"]) {  // the kinds to pick from, by name
      const Field type = FieldOf<LightRandomization>("type");
      l.kinds.clear();
      for (const auto& choice : ReadNameChoice(r, n["type"], at + ".type"))
        l.kinds.push_back(
            ReadKnown<LightSource::Kind>(r, choice.first, at + ".type", type, "light"));
    }
    if (n["per"])
      ReadField(r, n["per"], at + ".per", FieldOf<Randomization>("lights_per"), &d.lights_per);
    std::string why;
    if (!l.Check(&why)) r.Fail(n, at, why);
    d.lights = l;
  }
  if (const YAML::Node n = node["environment"]) {
    const std::string at = key + ".environment";
    r.ExpectKeys(n, at, SchemaAt("randomize.environment"));
    EnvironmentRandomization e;
    if (const YAML::Node images = n["images"]) {
      r.ExpectKeys(images, at + ".images", SchemaAt("randomize.environment.images"));
      if (!images["folder"])
        r.Fail(images, at + ".images", "give the 'folder' of equirectangular images to pick from");
      e.images = ReadImageFolder(r, images["folder"], at + ".images.folder");
    }
    ReadDescribed(r, n, at, &e);
    if (n["per"]) {
      ReadField(r, n["per"], at + ".per", FieldOf<Randomization>("environment_per"),
                &d.environment_per);
    }
    std::string why;
    if (!e.Check(&why)) r.Fail(n, at, why);
    d.environment = e;
  }
  if (const YAML::Node n = node["camera"]) {
    const std::string at = key + ".camera";
    r.ExpectKeys(n, at, SchemaAt("randomize.camera"));
    CameraRandomization c;
    ReadDescribed(r, n, at, &c);
    std::string why;
    if (!c.Check(&why)) r.Fail(n, at, why);
    d.camera = c;
  }
  if (node["distractors"]) ReadDistractors(r, node["distractors"], key + ".distractors", &spec);
  if (const YAML::Node n = node["background"]) {
    const std::string at = key + ".background";
    r.ExpectKeys(n, at, SchemaAt("randomize.background"));
    if (!n["folder"]) r.Fail(n, at, "give the 'folder' of photos to pick from");
    BackgroundRandomization b;
    b.images = ReadImageFolder(r, n["folder"], at + ".folder");
    if (n["per"]) {
      ReadField(r, n["per"], at + ".per", FieldOf<Randomization>("background_per"),
                &d.background_per);
    }
    d.background = std::move(b);
  }
  return spec;
}

// What a recipe's (or scene's) randomisation needs of the rest of the recipe.
void CheckRandomize(const Reader& r, const YAML::Node& node, const std::string& key,
                    const RandomizeSpec& spec, const RunSpec& run) {
  const Randomization& d = spec.draws;
  // Where a group's key is (a scene's randomize may inherit the group from the recipe's: then
  // the scene's randomize itself).
  const auto at = [&node](const char* group, const char* k) {
    const YAML::Node g = node[group];
    if (!g) return node;
    const YAML::Node n = g[k];
    return n ? n : g;
  };
  if (d.changes_look() && run.render.mode != RenderOptions::Mode::kPbr) {
    r.Fail(node, key,
           "materials, lights, the environment, exposure, white balance and background photos "
           "are randomised in render.mode: pbr (the fast mode takes the camera's pose jitter "
           "and distractors)");
  }
  if (const auto& e = d.environment) {
    const Environment::Kind kind = run.look.environment.kind;
    if (e->temperature_k && (kind != Environment::Kind::kUniform || e->images)) {
      r.Fail(at("environment", "temperature"), key + ".environment.temperature",
             e->images ? "tints a uniform environment's colour (images are drawn)"
                       : "tints a uniform environment's colour (lighting.environment is not "
                         "uniform)");
    }
    if (e->rotation_deg && kind != Environment::Kind::kImage && !e->images) {
      r.Fail(at("environment", "rotation"), key + ".environment.rotation",
             "turns an image environment (lighting.environment is not an image)");
    }
  }
  if (d.background && run.look.floor) {
    r.Fail(at("background", "folder"), key + ".background",
           "pastes photos where nothing is hit, but the floor fills every downward view: set "
           "render.floor: false");
  }
  if (!d.camera) return;
  for (const RigSensor& sensor : RunSensors(run)) {
    const std::string who = run.rig.empty() ? "camera" : "cameras '" + sensor.name + "'";
    if (const auto& gain = d.camera->noise_gain) {
      const YAML::Node where = at("camera", "noise_gain");
      if (!(sensor.sensor.imager.full_well > 0)) {
        r.Fail(where, key + ".camera.noise_gain",
               "scales the image noise: " + who + " has none (give it imager.full_well)");
      }
      // The noisiest and the quietest sensor it can draw must be sensors.
      const bool normal = gain->kind == Distribution::Kind::kNormal;
      for (const double g : {normal ? CameraRandomization::kMinNoiseGain : gain->Lowest(),
                             normal ? CameraRandomization::kMaxNoiseGain : gain->Highest()}) {
        ImageSensor s = sensor.sensor.imager;
        s.full_well /= g * g;
        s.read_noise /= g;
        std::string why;
        if (!s.Check(&why))
          r.Fail(where, key + ".camera.noise_gain", "a gain of " + std::to_string(g) + ": " + why);
      }
    }
    if ((d.camera->focus_distance_mm || d.camera->f_number) && !sensor.sensor.lens.active()) {
      r.Fail(at("camera", "f_number"), key + ".camera",
             "focus_distance and f_number draw the lens's: " + who +
                 " has no lens (give it lens.focal_length)");
    }
  }
}

}  // namespace cadsynth::recipe_detail
