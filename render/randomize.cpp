#include "render/randomize.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "cad/core/error.h"
#include "cad/core/random.h"
#include "render/image.h"
#include "render/sampling.h"

namespace cadsynth {

namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr uint64_t kPerScene = (uint64_t{1} << 40) - 1;
constexpr int kMaxLights = 64;
constexpr double kHuge = 1e300;
// Lengths drawn for lights and the lens: at most 100 m (a light's position, the focus distance
// stay inside the renderer's 1 km), a light at least 0.1 mm across.
constexpr double kFar = 1e5, kSmallest = 0.1;

// Linear RGB <-> HSV of the sRGB-encoded colour (h in turns, s and v in [0, 1]).
Eigen::Vector3f ToHsv(const Eigen::Vector3f& linear) {
  Eigen::Vector3f c;
  for (int i = 0; i < 3; ++i) c[i] = LinearToSrgb(std::clamp(linear[i], 0.0f, 1.0f));
  const float mx = c.maxCoeff(), mn = c.minCoeff(), d = mx - mn;
  float h = 0;
  if (d > 0) {
    if (mx == c[0]) {
      h = (c[1] - c[2]) / d;
    } else if (mx == c[1]) {
      h = 2 + (c[2] - c[0]) / d;
    } else {
      h = 4 + (c[0] - c[1]) / d;
    }
    h /= 6;
    h -= std::floor(h);
  }
  return {h, mx > 0 ? d / mx : 0.0f, mx};
}

Eigen::Vector3f FromHsv(const Eigen::Vector3f& hsv) {
  const float h = (hsv[0] - std::floor(hsv[0])) * 6, s = hsv[1], v = hsv[2];
  const int sector = std::min(5, static_cast<int>(h));
  const float f = h - sector, p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  Eigen::Vector3f c;
  switch (sector) {
    case 0:
      c = {v, t, p};
      break;
    case 1:
      c = {q, v, p};
      break;
    case 2:
      c = {p, v, t};
      break;
    case 3:
      c = {p, q, v};
      break;
    case 4:
      c = {t, p, v};
      break;
    default:
      c = {v, p, q};
      break;
  }
  for (int i = 0; i < 3; ++i) c[i] = SrgbToLinear(std::clamp(c[i], 0.0f, 1.0f));
  return c;
}

bool CheckOptional(const std::optional<Distribution>& d, const char* name, std::string* why) {
  if (!d) return true;
  if (!d->Check(why)) {
    *why = std::string(name) + ": " + *why;
    return false;
  }
  return true;
}

// A distribution whose draws must stay inside [lo, hi] (factors above 0, kelvin on the locus).
bool CheckRange(const std::optional<Distribution>& d, const char* name, double lo, double hi,
                std::string* why) {
  if (!CheckOptional(d, name, why)) return false;
  if (d && !(d->Lowest() >= lo && d->Highest() <= hi)) {
    *why = std::string(name) + ": draws must lie in [" + std::to_string(lo) + ", " +
           std::to_string(hi) + "] (a normal's mean; its tails are clipped to them)";
    return false;
  }
  return true;
}

// Draws quantity `name` from `d` with the frame's seed and records it.
class Drawer {
 public:
  explicit Drawer(std::vector<Drawn>* record) : record_(record) {}
  // Draws that fall outside [lo, hi] (a normal's tails) are clipped to it; the record keeps the
  // value used.
  double operator()(uint64_t seed, const Distribution& d, const std::string& name,
                    double lo = -kHuge, double hi = kHuge) {
    const double v = std::clamp(d.Draw(seed, "randomize.draw." + name), lo, hi);
    record_->push_back({name, {v}, ""});
    return v;
  }
  // One of n things, equally likely (the caller records which by name).
  size_t Pick(uint64_t seed, size_t n, const std::string& name) {
    if (n == 0) throw Error("randomize: " + name + ": nothing to pick from");
    return std::min(n - 1, static_cast<size_t>(UniformDraw(seed, "randomize.draw." + name, 0) * n));
  }
  void Text(const std::string& name, const std::string& text) {
    record_->push_back({name, {}, text});
  }
  void Numbers(const std::string& name, std::vector<double> values) {
    record_->push_back({name, std::move(values), ""});
  }

 private:
  std::vector<Drawn>* record_;
};

// A unit vector uniform on the sphere from two draws of quantity `name`.
Eigen::Vector3d UniformDirection(uint64_t seed, const std::string& name) {
  const std::string stream = "randomize.draw." + name;
  const double z = 2 * UniformDraw(seed, stream, 0) - 1;
  const double phi = 2 * M_PI * UniformDraw(seed, stream, 1);
  const double r = std::sqrt(std::max(0.0, 1 - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

// `base` redrawn by `m`; `own_color` is the part's colour for presets that take it.
Material DrawMaterial(const MaterialRandomization& m, const Material& base,
                      const Eigen::Vector3f& own_color, uint64_t seed, const std::string& prefix,
                      Drawer& draw) {
  Material out = base;
  if (!m.presets.empty()) {
    const size_t i = draw.Pick(seed, m.presets.size(), prefix + ".preset");
    draw.Text(prefix + ".preset", m.preset_names[i]);
    out = m.presets[i];
    if (out.base_from_part) out.surface.base_color = own_color;
  }
  if (!m.textures.empty()) {
    const size_t i = draw.Pick(seed, m.textures.size(), prefix + ".texture");
    draw.Text(prefix + ".texture", m.texture_names[i]);
    out.texture = m.textures[i];
  }
  if (m.hue || m.saturation || m.value) {
    Eigen::Vector3f hsv = ToHsv(out.surface.base_color);
    if (m.hue) hsv[0] += static_cast<float>(draw(seed, *m.hue, prefix + ".hue"));
    if (m.saturation)
      hsv[1] = std::clamp(
          hsv[1] * static_cast<float>(draw(seed, *m.saturation, prefix + ".saturation", 0, kHuge)),
          0.0f, 1.0f);
    if (m.value)
      hsv[2] =
          std::clamp(hsv[2] * static_cast<float>(draw(seed, *m.value, prefix + ".value", 0, kHuge)),
                     0.0f, 1.0f);
    out.surface.base_color = FromHsv(hsv);
  }
  const auto unit = [&](const std::optional<Distribution>& d, const char* name, float* value) {
    if (d) *value = static_cast<float>(draw(seed, *d, prefix + "." + name, 0, 1));
  };
  unit(m.metallic, "metallic", &out.surface.metallic);
  unit(m.roughness, "roughness", &out.surface.roughness);
  unit(m.specular, "specular", &out.surface.specular);
  if (m.texture_scale)
    out.texture.scale_mm *= draw(seed, *m.texture_scale, prefix + ".texture_scale", 1e-3, 1e3);
  return out;
}

}  // namespace

const char* LightKindName(LightSource::Kind kind) {
  switch (kind) {
    case LightSource::Kind::kPoint:
      return "point";
    case LightSource::Kind::kSpot:
      return "spot";
    case LightSource::Kind::kRect:
      return "rect";
    case LightSource::Kind::kDisc:
      return "disc";
    case LightSource::Kind::kSun:
      return "sun";
  }
  return "";
}

bool Distribution::Check(std::string* why) const {
  const auto finite = [](double v) { return std::isfinite(v); };
  switch (kind) {
    case Kind::kFixed:
      if (finite(a)) return true;
      *why = "the value is not a finite number";
      return false;
    case Kind::kUniform:
      if (!finite(a) || !finite(b) || a > b) {
        *why = "uniform: [low, high] with low <= high, got [" + std::to_string(a) + ", " +
               std::to_string(b) + "]";
        return false;
      }
      return true;
    case Kind::kLogUniform:
      if (!finite(a) || !finite(b) || !(a > 0) || a > b) {
        *why = "log_uniform: [low, high] with 0 < low <= high, got [" + std::to_string(a) + ", " +
               std::to_string(b) + "]";
        return false;
      }
      return true;
    case Kind::kNormal:
      if (!finite(a) || !finite(b) || b < 0) {
        *why = "normal: [mean, sigma] with sigma >= 0, got [" + std::to_string(a) + ", " +
               std::to_string(b) + "]";
        return false;
      }
      return true;
    case Kind::kChoice:
      if (values.empty()) {
        *why = "choice: the list is empty";
        return false;
      }
      if (!std::all_of(values.begin(), values.end(), finite)) {
        *why = "choice: a value is not a finite number";
        return false;
      }
      return true;
  }
  return false;
}

double Distribution::Draw(uint64_t seed, const std::string& stream) const {
  switch (kind) {
    case Kind::kFixed:
      return a;
    case Kind::kUniform:
      return a + (b - a) * UniformDraw(seed, stream, 0);
    case Kind::kLogUniform:
      return std::exp(std::log(a) + (std::log(b) - std::log(a)) * UniformDraw(seed, stream, 0));
    case Kind::kNormal: {
      const double u1 = 1.0 - UniformDraw(seed, stream, 0);  // (0, 1]
      const double u2 = UniformDraw(seed, stream, 1);
      return a + b * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
    }
    case Kind::kChoice: {
      const size_t i = std::min(values.size() - 1,
                                static_cast<size_t>(UniformDraw(seed, stream, 0) * values.size()));
      return values[i];
    }
  }
  return a;
}

double Distribution::Lowest() const {
  switch (kind) {
    case Kind::kNormal:
      return a;
    case Kind::kChoice:
      return *std::min_element(values.begin(), values.end());
    default:
      return a;
  }
}

double Distribution::Highest() const {
  switch (kind) {
    case Kind::kFixed:
      return a;
    case Kind::kNormal:
      return a;
    case Kind::kChoice:
      return *std::max_element(values.begin(), values.end());
    default:
      return b;
  }
}

bool MaterialRandomization::Check(std::string* why) const {
  if (presets.size() != preset_names.size() || textures.size() != texture_names.size()) {
    *why = "presets and textures: a name for each";
    return false;
  }
  for (const Texture& t : textures) {
    if (t.kind != Texture::Kind::kImage || !t.pixels || !(t.scale_mm > 0)) {
      *why = "textures: image textures with their pixels and a positive scale";
      return false;
    }
  }
  std::string w;
  for (const Material& m : presets) {
    if (!m.Check(&w)) {
      *why = "presets: " + w;
      return false;
    }
  }
  return CheckOptional(hue, "hue", why) && CheckRange(saturation, "saturation", 0, 1e6, why) &&
         CheckRange(value, "value", 0, 1e6, why) && CheckRange(metallic, "metallic", 0, 1, why) &&
         CheckRange(roughness, "roughness", 0, 1, why) &&
         CheckRange(specular, "specular", 0, 1, why) &&
         CheckRange(texture_scale, "texture_scale", 1e-3, 1e3, why);
}

bool LightRandomization::Check(std::string* why) const {
  const auto check = [&](const Distribution& d, const char* name, double lo, double hi) {
    return CheckRange(std::optional<Distribution>(d), name, lo, hi, why);
  };
  if (kinds.empty()) {
    *why = "type: no light types to pick from";
    return false;
  }
  return check(count, "count", 0, kMaxLights) && check(elevation_deg, "elevation", 0, 90) &&
         check(azimuth_deg, "azimuth", -1e6, 1e6) && check(distance_mm, "distance", 1, kFar) &&
         check(power, "power", 0, 1e12) && check(temperature_k, "temperature", 1667, 25000) &&
         check(size_mm, "size", kSmallest, kFar);
}

bool ImageChoice::Check(std::string* why) const {
  if (files.empty() || pixels.size() != files.size() || names.size() != files.size()) {
    *why = "images: at least one, each with its pixels and name";
    return false;
  }
  for (const auto& p : pixels) {
    if (!p || p->width <= 0 || p->height <= 0) {
      *why = "images: each with its pixels";
      return false;
    }
  }
  return true;
}

bool EnvironmentRandomization::Check(std::string* why) const {
  if (images && !images->Check(why)) return false;
  return CheckRange(strength, "strength", 0, 1e12, why) &&
         CheckOptional(rotation_deg, "rotation", why) &&
         CheckRange(temperature_k, "temperature", 1667, 25000, why);
}

bool CameraRandomization::Check(std::string* why) const {
  return CheckRange(exposure, "exposure", -20, 20, why) &&
         CheckRange(white_balance_k, "white_balance", 1667, 25000, why) &&
         CheckRange(noise_gain, "noise_gain", CameraRandomization::kMinNoiseGain,
                    CameraRandomization::kMaxNoiseGain, why) &&
         CheckRange(focus_distance_mm, "focus_distance", 1, kFar, why) &&
         CheckRange(f_number, "f_number", 0.5, 128, why) &&
         CheckRange(rotation_deg, "rotation", -180, 180, why) &&
         CheckRange(translation_mm, "translation", -1e6, 1e6, why);
}

bool DistractorRandomization::Check(std::string* why) const {
  if (!CheckRange(count, "count", 0, kMaxCount, why) || !CheckRange(size_mm, "size", 1, 10000, why))
    return false;
  if (material && !material->Check(why)) {
    *why = "material." + *why;
    return false;
  }
  return true;
}

bool Randomization::changes_look() const {
  return !parts.empty() || floor || fixtures || lights || environment ||
         (camera && (camera->exposure || camera->white_balance_k)) ||
         (distractors && distractors->material) || background;
}

bool Randomization::Check(std::string* why) const {
  std::string w;
  for (size_t i = 0; i < parts.size(); ++i) {
    if (!parts[i].material.Check(&w)) {
      *why = "parts[" + std::to_string(i) + "]." + w;
      return false;
    }
  }
  const auto sub = [&](const auto& group, const char* name) {
    if (!group || group->Check(&w)) return true;
    *why = std::string(name) + "." + w;
    return false;
  };
  return sub(floor, "floor") && sub(fixtures, "fixtures") && sub(lights, "lights") &&
         sub(environment, "environment") && sub(camera, "camera") &&
         sub(distractors, "distractors") && sub(background, "background");
}

namespace {
uint64_t RunSeed(const Randomization& r) { return Hash(streams::kRandomizeFrame.id(), r.seed); }
uint64_t SceneSeed(const Randomization& r, uint64_t scene) {
  return Hash(RunSeed(r), (scene << 40) + kPerScene);
}
}  // namespace

std::vector<DistractorPick> DrawDistractors(const Randomization& r, uint64_t scene,
                                            const std::vector<std::string>& names,
                                            const std::vector<int>& sizes,
                                            std::vector<Drawn>* record) {
  std::vector<DistractorPick> picks;
  if (!r.distractors || names.empty() || sizes.size() != names.size()) return picks;
  const DistractorRandomization& d = *r.distractors;
  const uint64_t seed = SceneSeed(r, scene);
  Drawer draw(record);
  const int count = std::clamp(
      static_cast<int>(std::lround(draw(seed, d.count, "distractor.count", 0, d.kMaxCount))), 0,
      DistractorRandomization::kMaxCount);
  for (int k = 0; k < count; ++k) {
    const std::string p = "distractor." + std::to_string(k);
    DistractorPick pick;
    pick.object = static_cast<int>(draw.Pick(seed, names.size(), p + ".object"));
    draw.Text(p + ".object", names[static_cast<size_t>(pick.object)]);
    // Always three draws (an object's sizes do not depend on which object another one is).
    for (int i = 0; i < 3; ++i) {
      pick.size_mm[i] = std::clamp(
          d.size_mm.Draw(seed, "randomize.draw." + p + ".size." + std::to_string(i)), 1.0, 1e4);
    }
    const int used = std::clamp(sizes[static_cast<size_t>(pick.object)], 0, 3);
    if (used > 0)
      draw.Numbers(p + ".size",
                   std::vector<double>(pick.size_mm.data(), pick.size_mm.data() + used));
    const std::string stream = "randomize.draw." + p + ".color";
    const double h = UniformDraw(seed, stream, 0), sat = 0.1 + 0.8 * UniformDraw(seed, stream, 1),
                 val = 0.15 + 0.75 * UniformDraw(seed, stream, 2);
    const Eigen::Vector3f linear = FromHsv(Eigen::Vector3f(h, sat, val));
    for (int c = 0; c < 3; ++c) pick.color[c] = LinearToSrgb(linear[c]);
    draw.Numbers(p + ".color", {pick.color.x(), pick.color.y(), pick.color.z()});
    picks.push_back(pick);
  }
  return picks;
}

uint64_t DistractorDropSeed(const Randomization& r, uint64_t scene) {
  return Hash(SceneSeed(r, scene), Fnv1a64("randomize.draw.distractor.drop"));
}

FrameDraw DrawFrame(const Randomization& r, const FrameLook& base,
                    const Eigen::Isometry3d& world_from_cam, const SensorOptions& sensor,
                    const Eigen::Vector3d& centre, uint64_t scene, uint64_t view) {
  FrameDraw out;
  out.look = base;
  out.world_from_cam = world_from_cam;
  out.sensor = sensor;
  out.record = r.scene_record;
  Drawer draw(&out.record);
  const uint64_t run_seed = RunSeed(r);
  const auto seed_of = [&](DrawPer per) {
    return Hash(run_seed, (scene << 40) + (per == DrawPer::kScene ? kPerScene : view));
  };

  if (!r.parts.empty()) {
    // Per part: every copy draws the same numbers (the key names the part), recorded once.
    std::set<std::string> recorded;
    for (size_t i = 0; i < base.instance_materials.size() && i < r.instance_rule.size(); ++i) {
      const int rule = r.instance_rule[i];
      if (rule < 0) continue;
      const PartRandomization& p = r.parts[static_cast<size_t>(rule)];
      const uint64_t seed = seed_of(p.per);
      const std::string prefix =
          p.per_instance
              ? "instance." + std::to_string(i)
              : "part." + std::to_string(i < r.instance_part.size() ? r.instance_part[i] : 0);
      std::vector<Drawn> scratch;
      Drawer quiet(&scratch);
      const bool first = recorded.insert(prefix).second;
      const Eigen::Vector3f own = i < base.instance_colors.size() ? base.instance_colors[i]
                                                                  : Eigen::Vector3f::Constant(0.5f);
      out.look.instance_materials[i] = DrawMaterial(p.material, base.instance_materials[i], own,
                                                    seed, prefix, first ? draw : quiet);
    }
  }
  if (r.floor) {
    out.look.floor = DrawMaterial(*r.floor, base.floor, base.floor.surface.base_color,
                                  seed_of(r.floor_per), "floor", draw);
  }
  for (size_t f = 0; f < base.fixture_materials.size(); ++f) {
    // Containers and the like take `fixtures`; distractors (the last fixtures) their own.
    const bool distractor = r.distractors && f >= r.first_distractor;
    const Material& m = base.fixture_materials[f];
    if (!distractor && r.fixtures) {
      out.look.fixture_materials[f] =
          DrawMaterial(*r.fixtures, m, m.surface.base_color, seed_of(r.fixtures_per),
                       "fixture." + std::to_string(f), draw);
    } else if (distractor && r.distractors->material) {
      out.look.fixture_materials[f] = DrawMaterial(
          *r.distractors->material, m, m.surface.base_color, seed_of(r.distractors->material_per),
          "distractor." + std::to_string(f - r.first_distractor), draw);
    }
  }
  if (r.lights) {
    const LightRandomization& l = *r.lights;
    const uint64_t seed = seed_of(r.lights_per);
    const int count =
        std::clamp(static_cast<int>(std::lround(draw(seed, l.count, "light.count", 0, kMaxLights))),
                   0, kMaxLights);
    if (!l.keep) out.look.lights.clear();
    for (int i = 0; i < count; ++i) {
      const std::string p = "light." + std::to_string(i);
      LightSource s;
      s.kind = l.kinds[draw.Pick(seed, l.kinds.size(), p + ".type")];
      draw.Text(p + ".type", LightKindName(s.kind));
      const double el = draw(seed, l.elevation_deg, p + ".elevation", 0, 90) * kDeg;
      const double az = draw(seed, l.azimuth_deg, p + ".azimuth") * kDeg;
      const double dist = draw(seed, l.distance_mm, p + ".distance", 1, kFar);
      s.power = draw(seed, l.power, p + ".power", 0, kHuge);
      s.color = BlackbodyColor(draw(seed, l.temperature_k, p + ".temperature", 1667, 25000));
      const double size = draw(seed, l.size_mm, p + ".size", kSmallest, kFar);
      const Eigen::Vector3d offset(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                                   std::sin(el));
      s.position = centre + dist * offset;
      s.direction = -offset;
      s.size_x_mm = s.size_y_mm = size;
      s.radius_mm = 0.5 * size;
      out.look.lights.push_back(s);
    }
  }
  if (r.environment) {
    const EnvironmentRandomization& e = *r.environment;
    const uint64_t seed = seed_of(r.environment_per);
    Environment& env = out.look.environment;
    if (e.images) {
      const size_t i = draw.Pick(seed, e.images->files.size(), "environment.image");
      draw.Text("environment.image", e.images->names[i]);
      env.kind = Environment::Kind::kImage;
      env.image = e.images->files[i];
      env.pixels = e.images->pixels[i];
    }
    if (e.strength)
      env.strength = static_cast<float>(draw(seed, *e.strength, "environment.strength", 0, kHuge));
    if (e.rotation_deg)
      env.rotation_rad = draw(seed, *e.rotation_deg, "environment.rotation") * kDeg;
    if (e.temperature_k) {
      // The colour's luminance kept, its hue a black body's (what exceeds 1 moves into the
      // strength).
      const Eigen::Vector3f bb =
          BlackbodyColor(draw(seed, *e.temperature_k, "environment.temperature", 1667, 25000));
      Eigen::Vector3f c = bb * (Luminance(env.color) / Luminance(bb));
      if (c.maxCoeff() > 1.0f) {
        env.strength *= c.maxCoeff();
        c /= c.maxCoeff();
      }
      env.color = c;
    }
  }
  if (r.background) {
    const ImageChoice& images = r.background->images;
    const size_t i = draw.Pick(seed_of(r.background_per), images.files.size(), "background");
    draw.Text("background", images.names[i]);
    out.look.background = images.pixels[i];
  }
  if (r.camera) {
    const CameraRandomization& c = *r.camera;
    const uint64_t seed = seed_of(DrawPer::kFrame);
    if (c.exposure) out.look.exposure += draw(seed, *c.exposure, "camera.exposure", -20, 20);
    if (c.white_balance_k)
      out.look.white_balance =
          WhiteBalanceGains(draw(seed, *c.white_balance_k, "camera.white_balance", 1667, 25000));
    if (c.noise_gain) {
      // The noise's standard deviation times g: the full well shrinks by g^2, the read noise
      // (in electrons of the smaller well) by g.
      const double g = draw(seed, *c.noise_gain, "camera.noise_gain",
                            CameraRandomization::kMinNoiseGain, CameraRandomization::kMaxNoiseGain);
      out.sensor.imager.full_well /= g * g;
      out.sensor.imager.read_noise /= g;
    }
    if (c.focus_distance_mm)
      out.sensor.lens.focus_distance_mm =
          draw(seed, *c.focus_distance_mm, "camera.focus_distance", 1, kFar);
    if (c.f_number) out.sensor.lens.f_number = draw(seed, *c.f_number, "camera.f_number", 0.5, 128);
    if (c.rotation_deg) {
      const double angle = c.rotation_deg->Draw(seed, "randomize.draw.camera.rotation");
      const Eigen::Vector3d axis = UniformDirection(seed, "camera.rotation_axis");
      draw.Numbers("camera.rotation", {angle, axis.x(), axis.y(), axis.z()});
      out.world_from_cam.linear() =
          (out.world_from_cam.linear() * Eigen::AngleAxisd(angle * kDeg, axis)).eval();
    }
    if (c.translation_mm) {
      const double length = c.translation_mm->Draw(seed, "randomize.draw.camera.translation");
      const Eigen::Vector3d dir = UniformDirection(seed, "camera.translation_direction");
      draw.Numbers("camera.translation", {length, dir.x(), dir.y(), dir.z()});
      out.world_from_cam.translation() += world_from_cam.linear() * (length * dir);
    }
  }
  return out;
}

Eigen::Vector3f BlackbodyColor(double kelvin) {
  const double t = std::clamp(kelvin, 1667.0, 25000.0);
  const double t2 = t * t, t3 = t2 * t;
  const double x = t <= 4000 ? -0.2661239e9 / t3 - 0.2343589e6 / t2 + 0.8776956e3 / t + 0.179910
                             : -3.0258469e9 / t3 + 2.1070379e6 / t2 + 0.2226347e3 / t + 0.240390;
  const double x2 = x * x, x3 = x2 * x;
  double y;
  if (t <= 2222) {
    y = -1.1063814 * x3 - 1.34811020 * x2 + 2.18555832 * x - 0.20219683;
  } else if (t <= 4000) {
    y = -0.9549476 * x3 - 1.37418593 * x2 + 2.09137015 * x - 0.16748867;
  } else {
    y = 3.0817580 * x3 - 5.87338670 * x2 + 3.75112997 * x - 0.37001483;
  }
  const double X = x / y, Y = 1.0, Z = (1 - x - y) / y;
  Eigen::Vector3d rgb(3.2404542 * X - 1.5371385 * Y - 0.4985314 * Z,
                      -0.9692660 * X + 1.8760108 * Y + 0.0415560 * Z,
                      0.0556434 * X - 0.2040259 * Y + 1.0572252 * Z);
  rgb = rgb.cwiseMax(0.0);
  return (rgb / rgb.maxCoeff()).cast<float>();
}

Eigen::Vector3f WhiteBalanceGains(double kelvin) {
  const Eigen::Vector3f g = BlackbodyColor(6504.0).cwiseQuotient(BlackbodyColor(kelvin));
  return g / g.y();
}

}  // namespace cadsynth
