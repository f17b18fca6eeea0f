#include "render/scene.h"

#include <cmath>

namespace cadsynth {

Eigen::Vector3f PaletteColor(int index) {
  // Hues spread by the golden angle, fairly saturated, never grey (the floor is grey).
  const float hue = std::fmod(0.08f + 0.61803398875f * static_cast<float>(index), 1.0f) * 6.0f;
  const float s = 0.65f, v = 0.9f;
  const int sector = static_cast<int>(hue) % 6;
  const float f = hue - std::floor(hue);
  const float p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  switch (sector) {
    case 0:
      return {v, t, p};
    case 1:
      return {q, v, p};
    case 2:
      return {p, v, t};
    case 3:
      return {p, q, v};
    case 4:
      return {t, p, v};
    default:
      return {v, p, q};
  }
}

}  // namespace cadsynth
