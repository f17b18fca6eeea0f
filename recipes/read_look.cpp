// The look: the fast mode's options and lights, materials and textures, light sources and the
// environment.
#include "recipes/sections.h"

namespace cadsynth::recipe_detail {

void ReadRender(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  ReadFields(r, node, "render", &spec->render, SchemaAt("render"));
  // The fast mode's look (Scene::Fields) and its lights (Scene::Light::Fields).
  Scene& look = spec->look;
  ReadDescribed(r, node, "render", &look);
  if (node["lights"]) {
    const YAML::Node lights = node["lights"];
    if (!lights.IsSequence())
      r.Fail(lights, "render.lights",
             "expected a list of {direction: [x, y, z]} or {position: [x, y, z]}");
    look.lights.clear();
    for (size_t i = 0; i < lights.size(); ++i) {
      const std::string key = "render.lights[" + std::to_string(i) + "]";
      r.ExpectKeys(lights[i], key, SchemaAt("render.lights[]"));
      if (!lights[i]["direction"] == !lights[i]["position"])
        r.Fail(lights[i], key, "give a direction or a position");
      Scene::Light light;
      ReadDescribed(r, lights[i], key, &light);
      light.kind =
          lights[i]["direction"] ? Scene::Light::Kind::kDirectional : Scene::Light::Kind::kPoint;
      if (light.kind == Scene::Light::Kind::kDirectional && light.direction.norm() == 0)
        r.Fail(lights[i]["direction"], key + ".direction", "the direction must not be zero");
      look.lights.push_back(light);
    }
  }
  if (node["colors"]) {
    // A bool's choices (RunSpec::Fields) are false first; the message names cad first.
    const std::string colors = r.Scalar(node["colors"], "render.colors");
    if (!Choose(FieldOf<RunSpec>("colors"), colors, &spec->cad_colors))
      r.Fail(node["colors"], "render.colors", "expected 'cad' or 'palette', got '" + colors + "'");
  }
  r.Check(spec->render, node, "render");
}

namespace {

// A texture's keys over `texture` (a preset's, or none): its type first (a new type starts from
// that type's defaults), the described keys, then an image's pixels and projection.
void ReadTexture(const Reader& r, const YAML::Node& t, const std::string& key, Texture* texture) {
  const Field type = FieldOf<Texture>("type");
  // The message lists the patterns, then none.
  std::vector<std::string> known(type.choices.begin() + 1, type.choices.end());
  known.emplace_back(type.choices[0]);
  const auto kind = ReadKnown<Texture::Kind>(r, t["type"], key + ".type", type, "texture", known);
  if (kind != texture->kind) *texture = Texture{};
  texture->kind = kind;
  ReadDescribed(r, t, key, texture);
  if (t["seed"]) texture->seed = static_cast<uint64_t>(r.Integer(t["seed"], key + ".seed"));
  if (texture->kind == Texture::Kind::kImage) {
    if (!t["file"]) r.Fail(t, key, "an image texture needs a 'file'");
    try {
      texture->pixels = LoadLinearImage(texture->image);
    } catch (const Error& e) {
      r.Fail(t["file"], key + ".file", e.what());
    }
    if (const YAML::Node p = t["projection"]) {
      texture->projection = ReadKnown<Texture::Projection>(
          r, p, key + ".projection", FieldOf<Texture>("projection"), "projection");
    }
  } else if (t["file"]) {
    r.Fail(t["file"], key + ".file", "only an image texture reads a file");
  } else if (t["projection"]) {
    r.Fail(t["projection"], key + ".projection",
           "only an image texture is projected (procedural ones are solid)");
  }
}

}  // namespace

// A material: a preset, then the keys that change it, and a texture.
Material ReadMaterial(const Reader& r, const YAML::Node& node, const std::string& key,
                      const Key& schema) {
  r.ExpectKeys(node, key, schema);
  Material m;
  if (node["preset"]) {
    const std::string name = r.Scalar(node["preset"], key + ".preset");
    if (!MaterialPreset(name, &m)) {
      const std::string known = JoinNames(MaterialPresetNames());
      const std::string best = NearestName(name, MaterialPresetNames());
      r.Fail(node["preset"], key + ".preset",
             "unknown material '" + name + "'" +
                 (best.empty() ? "" : " (did you mean '" + best + "'?)") + "; known: " + known);
    }
  }
  if (const YAML::Node c = node["base_color"]) {
    if (c.IsScalar() && c.Scalar() == "cad") {
      m.base_from_part = true;
    } else {
      m.surface.base_color = r.LinearColor(c, key + ".base_color");
      m.base_from_part = false;
    }
  }
  ReadDescribed(r, node, key, &m.surface);
  ReadDescribed(r, node, key, &m);
  if (const YAML::Node t = node["texture"]) {
    const std::string tkey = key + ".texture";
    if (t.IsScalar() && t.Scalar() == "none") {
      m.texture = Texture{};
    } else {
      if (!t.IsMap() || !t["type"]) r.Fail(t, tkey, "a texture needs a 'type'");
      r.ExpectKeys(t, tkey, SchemaAt("materials.floor.texture"));
      ReadTexture(r, t, tkey, &m.texture);
    }
  }
  r.Check(m, node, key);
  return m;
}

void ReadMaterials(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  r.ExpectKeys(node, "materials", SchemaAt("materials"));
  if (node["floor"]) {
    spec->look.floor_material =
        ReadMaterial(r, node["floor"], "materials.floor", SchemaAt("materials.floor"));
    if (spec->look.floor_material.texture.projection == Texture::Projection::kUv)
      r.Fail(node["floor"], "materials.floor",
             "the floor has no texture coordinates: use projection 'triplanar' (or 'auto')");
  }
  if (node["default"])
    spec->default_material =
        ReadMaterial(r, node["default"], "materials.default", SchemaAt("materials.default"));
  if (const YAML::Node assign = node["assign"]) {
    if (!assign.IsSequence())
      r.Fail(assign, "materials.assign",
             "expected a list of {name|family|file: pattern, preset: ..., ...}");
    for (size_t i = 0; i < assign.size(); ++i) {
      const std::string key = "materials.assign[" + std::to_string(i) + "]";
      const YAML::Node item = assign[i];
      MaterialRule rule;
      rule.where = r.Where(item);
      rule.material = ReadMaterial(r, item, key, SchemaAt("materials.assign[]"));
      ReadPartPatterns(r, item, key, &rule);
      spec->material_rules.push_back(std::move(rule));
    }
  }
}

namespace {

// A direction as [x, y, z], or towards a `target` point from `position`.
Eigen::Vector3d ReadAim(const Reader& r, const YAML::Node& node, const std::string& key,
                        const Eigen::Vector3d& position, const Eigen::Vector3d& fallback) {
  if (node["direction"] && node["target"])
    r.Fail(node["target"], key + ".target", "give 'direction' or 'target', not both");
  if (node["direction"]) {
    const Eigen::Vector3d d = Triple(r, node["direction"], key + ".direction", false);
    if (d.norm() == 0) r.Fail(node["direction"], key + ".direction", "must not be zero");
    return d;
  }
  if (node["target"]) {
    const Eigen::Vector3d d = Triple(r, node["target"], key + ".target", true) - position;
    if (d.norm() == 0) r.Fail(node["target"], key + ".target", "is the light's own position");
    return d;
  }
  return fallback;
}

LightSource ReadLightSource(const Reader& r, const YAML::Node& node, const std::string& key) {
  if (!node.IsMap()) r.Fail(node, key, "expected a mapping of keys to values");
  if (!node["type"]) r.Fail(node, key, "a light needs a 'type': point, spot, rect, disc or sun");
  LightSource l;
  using K = LightSource::Kind;
  l.kind = ReadKnown<K>(r, node["type"], key + ".type", FieldOf<LightSource>("type"), "light");
  if (l.kind == K::kSun && node["power"])
    r.Fail(node["power"], key + ".power", "a sun's is 'strength' (irradiance, W/m2, as Blender's)");
  if (l.kind != K::kSun && node["strength"])
    r.Fail(node["strength"], key + ".strength", "this light's is 'power' (W, as Blender's)");
  r.ExpectKeys(node, key, SchemaAt("lighting.lights[]"));
  ReadDescribed(r, node, key, &l);
  if (l.kind != K::kPoint) l.direction = ReadAim(r, node, key, l.position, l.direction);
  // The sun's power is its `strength` (irradiance), as in Blender.
  const char* amount = l.kind == K::kSun ? "strength" : "power";
  if (!node[amount]) {
    r.Fail(node, key,
           l.kind == K::kSun ? "a sun needs a 'strength' (irradiance, W/m2, as Blender's)"
                             : "a light needs a 'power' (W, as Blender's)");
  }
  ReadField(r, node[amount], key + "." + amount, FieldOf<LightSource>("power"), &l.power);
  if (l.kind == K::kDisc && !node["radius"]) r.Fail(node, key, "a disc light needs a 'radius'");
  if (const YAML::Node size = node["size"]) {
    if (size.IsScalar()) {
      l.size_x_mm = l.size_y_mm = r.Length(size, key + ".size");
    } else if (size.IsSequence() && size.size() == 2) {
      l.size_x_mm = r.Length(size[0], key + ".size");
      l.size_y_mm = r.Length(size[1], key + ".size");
    } else {
      r.Fail(size, key + ".size", "expected a length or [x, y]");
    }
  }
  r.Check(l, node, key);
  return l;
}

}  // namespace

void ReadLighting(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  r.ExpectKeys(node, "lighting", SchemaAt("lighting"));
  if (const YAML::Node lights = node["lights"]) {
    if (!lights.IsSequence())
      r.Fail(lights, "lighting.lights", "expected a list of {type: point|spot|rect|disc|sun, ...}");
    spec->look.light_sources.clear();
    for (size_t i = 0; i < lights.size(); ++i) {
      spec->look.light_sources.push_back(
          ReadLightSource(r, lights[i], "lighting.lights[" + std::to_string(i) + "]"));
    }
  }
  if (const YAML::Node env = node["environment"]) {
    const std::string key = "lighting.environment";
    Environment& e = spec->look.environment;
    if (!env.IsMap()) r.Fail(env, key, "expected a mapping of keys to values");
    e.kind = env["type"] ? ReadKnown<Environment::Kind>(r, env["type"], key + ".type",
                                                        FieldOf<Environment>("type"), "environment")
                         : Environment::Kind::kUniform;
    r.ExpectKeys(env, key, SchemaAt("lighting.environment"));
    if (e.kind == Environment::Kind::kImage && !env["file"])
      r.Fail(env, key, "an image environment needs a 'file' (HDR, EXR, ...)");
    // Colours are linear radiance multipliers (Blender's world colour).
    ReadDescribed(r, env, key, &e);
    if (env["file"]) {
      try {
        e.pixels = LoadLinearImage(e.image);
      } catch (const Error& err) {
        r.Fail(env["file"], key + ".file", err.what());
      }
    }
    r.Check(e, env, key);
  }
}

}  // namespace cadsynth::recipe_detail
