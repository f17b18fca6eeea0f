// The recipe's sections as the reader reads them (recipes/ only): part sources and classes
// (read_parts.cpp), the camera, rig and sweep (read_camera.cpp), the look, materials and lights
// (read_look.cpp) and domain randomisation (read_randomize.cpp); recipe.cpp reads the scene, the
// output and the grasps and puts the recipe together. Each reads the described fields of its
// section through reader.h and by hand only the recipe's own syntax.
#pragma once

#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "recipes/reader.h"
#include "recipes/recipe.h"
#include "recipes/recipe_schema.h"
#include "variants/families.h"

namespace cadsynth::recipe_detail {

// --- Parts (read_parts.cpp) ---

// "spur_gear, ring_gear, ...": for unknown-family messages.
std::string KnownFamilies();

void ReadFamily(const Reader& r, const YAML::Node& item, const std::string& key,
                PartSource* source);

// `up`: the axis a file's designer drew as up (x, y, z, -x, -y, -z), turned to +z.
void ReadUp(const Reader& r, const YAML::Node& item, const std::string& key, PartSource* source);

// A file source's `file` (which must exist and have a known format), `unit` and `encoding`.
void ReadFileSource(const Reader& r, const YAML::Node& item, const std::string& key,
                    PartSource* source);

std::vector<PartSource> ReadParts(const Reader& r, const YAML::Node& node,
                                  const std::string& where);

void ReadClasses(const Reader& r, const YAML::Node& node, RunSpec* spec);

// Which parts a rule is for (MaterialRule, PhysicsRule): `name`, `family` and `file` patterns, at
// least one given; a family without glob characters must exist.
template <typename Rule>
void ReadPartPatterns(const Reader& r, const YAML::Node& item, const std::string& key, Rule* rule) {
  if (item["name"]) rule->name = r.Scalar(item["name"], key + ".name");
  if (item["family"]) {
    rule->family = r.Scalar(item["family"], key + ".family");
    if (FindFamily(rule->family) == nullptr &&
        rule->family.find_first_of("*?[") == std::string::npos) {
      r.Fail(item["family"], key + ".family",
             "unknown family '" + rule->family + "' (known: " + KnownFamilies() + ")");
    }
  }
  if (item["file"]) rule->file = r.Scalar(item["file"], key + ".file");
  if (rule->name.empty() && rule->family.empty() && rule->file.empty())
    r.Fail(item, key, "say which parts: 'name', 'family' or 'file' (a pattern)");
}

// --- Cameras and views (read_camera.cpp) ---

// A camera's keys (`camera:`, or an entry of `cameras:` with its `other` keys read elsewhere).
void ReadCamera(const Reader& r, const YAML::Node& node, const std::string& key, Intrinsics* kp,
                SensorOptions* sensor, const Key& schema);

void ReadSweep(const Reader& r, const YAML::Node& node, RunSpec* spec);

// `cameras:`, a rig: a list of cameras with names, the first one the rig's frame (the sweep
// places it) and the others fixed to it by `position` and `look_at` or `rotation`.
void ReadCameras(const Reader& r, const YAML::Node& node, RunSpec* spec);

// --- The look (read_look.cpp) ---

void ReadRender(const Reader& r, const YAML::Node& node, RunSpec* spec);

// A material: a preset, then the keys that change it, and a texture.
Material ReadMaterial(const Reader& r, const YAML::Node& node, const std::string& key,
                      const Key& schema);

void ReadMaterials(const Reader& r, const YAML::Node& node, RunSpec* spec);

void ReadLighting(const Reader& r, const YAML::Node& node, RunSpec* spec);

// --- Domain randomisation (read_randomize.cpp) ---

// `randomize:` (or a scene's, which replaces the groups it gives of `base`).
RandomizeSpec ReadRandomize(const Reader& r, const YAML::Node& node, const std::string& key,
                            const RandomizeSpec& base);

// What a recipe's (or scene's) randomisation needs of the rest of the recipe.
void CheckRandomize(const Reader& r, const YAML::Node& node, const std::string& key,
                    const RandomizeSpec& spec, const RunSpec& run);

}  // namespace cadsynth::recipe_detail
