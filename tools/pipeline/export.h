// The `variants` command: list a recipe's variants, and write each as a STEP file.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "recipes/recipe.h"

namespace cadsynth {

struct VariantListing {
  std::string id;              // scene/entry/family/index, as in variants.json
  std::string family;          // empty for files
  std::string params;          // "name=value, ..." or the file
  std::filesystem::path step;  // the written file (ExportVariants only)
};

// Every family variant of every scene (files are listed with their path), in recipe order.
std::vector<VariantListing> ListVariants(const RunSpec& spec);

// Builds every family variant and writes it as DIR/<id with '/' as '_'>.step (AP214, mm, exact
// B-rep with its parts, placements and names). Files named in the recipe are not exported. The
// folder appears complete or not at all. Throws Error naming the variant that cannot be built.
std::vector<VariantListing> ExportVariants(const RunSpec& spec, const std::filesystem::path& dir,
                                           bool overwrite);

}  // namespace cadsynth
