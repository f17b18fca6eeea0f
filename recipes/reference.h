// The recipe reference for the sections whose options are described once (cad/schema.h): every
// key with its default, kind and meaning, as `cadsynth generate --help-recipe` prints it.
#pragma once

#include <string>

namespace cadsynth {

std::string RecipeReference();

}  // namespace cadsynth
