// The recipe as one described tree (cad/core/schema.h's Key): every section, list and key a
// recipe may give, with its kind, its doc and, where it has one, its default. The reader takes
// each section's allowed keys from here; `cadsynth generate --help-recipe`, docs/recipes.md and
// the JSON Schema (`cadsynth generate --recipe-schema`) are written from it.
#pragma once

#include <string>
#include <string_view>

#include "cad/core/schema.h"

namespace cadsynth {

// The root: a section whose keys are the recipe's sections (parts, scene, ..., limits).
const Key& RecipeSchema();

// The key at `path`: section names joined by '.', "[]" for a list's item ("lighting.lights[]",
// "scenes[].container", "materials.assign[]"). Throws std::logic_error for a path the tree lacks
// (a reader asking for an undescribed section is a programming error).
const Key& SchemaAt(std::string_view path);

// The recipe reference: every key, section by section, with its kind, default and doc, as
// commented YAML (`cadsynth generate --help-recipe`; the generated part of docs/recipes.md).
std::string RecipeReference();

// A JSON Schema (draft 2020-12) of a recipe, for editors (the YAML language server) and checkers:
// unknown keys are errors, values are checked by kind.
std::string RecipeJsonSchema();

}  // namespace cadsynth
