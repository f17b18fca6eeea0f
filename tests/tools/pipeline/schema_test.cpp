// Every described option (cad/core/schema.h) reaches everything that must know it: a change of any
// one changes the run key, survives the shard file, is read from its recipe key, and is listed in
// the recipe reference and docs/recipes.md.
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <type_traits>

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "recipes/recipe_schema.h"
#include "tests/test_support.h"
#include "tools/pipeline/generate.h"
#include "tools/pipeline/journal.h"
#include "tools/pipeline/shards.h"

namespace cadsynth {
namespace {

// A described field's value as a recipe writes it (the reader's units: mm, radians with their
// unit, milliseconds, degrees).
template <typename T>
std::string RecipeText(const T& value, const Field& field) {
  if constexpr (std::is_floating_point_v<T>) {
    if (field.kind == "milliseconds") return FieldText(value * 1000.0, field);
  } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
    if (field.kind == "degrees3") return FieldText(Eigen::Vector3d(value * (180.0 / M_PI)), field);
  }
  return FieldText(value, field) + (field.kind == "length"  ? " mm"
                                    : field.kind == "angle" ? " rad"
                                                            : "");
}

// A value other than `value` that the options still accept where possible.
template <typename T>
T Changed(const T& value, const Field& field) {
  if constexpr (std::is_same_v<T, std::vector<double>>) {
    T longer = value;
    longer.push_back(1.5);
    return longer;
  } else if constexpr (std::is_same_v<T, std::vector<std::string>>) {  // names
    T longer = value;
    longer.push_back("x");
    return longer;
  } else if constexpr (IsVector<T>::value) {  // names of an enum's values
    T longer = value;
    longer.emplace_back();
    return longer;
  } else if constexpr (std::is_same_v<T, Distribution>) {
    // A value one more; a range half as wide (it stays inside the options' range).
    if (value.kind == Distribution::Kind::kFixed) return Distribution::Fixed(value.a + 1);
    T changed = value;
    changed.b = (value.a + value.b) / 2;
    if (value.kind == Distribution::Kind::kChoice) changed.values.push_back(value.values.back());
    return changed;
  } else if constexpr (std::is_same_v<T, std::optional<Distribution>>) {
    if (value) return Changed(*value, field);
    // Set, to a value the options accept (a colour temperature in kelvin).
    return Distribution::Fixed(field.key == "temperature" || field.key == "white_balance" ? 5000
                                                                                          : 1);
  } else if constexpr (std::is_enum_v<T>) {
    return static_cast<T>((static_cast<size_t>(value) + 1) %
                          std::max<size_t>(2, field.choices.size()));
  } else if constexpr (std::is_same_v<T, bool>) {
    return !value;
  } else if constexpr (std::is_same_v<T, std::string>) {
    return field.key == "isa" ? (value == "auto" ? "sse2" : "auto") : value + "x";
  } else if constexpr (std::is_same_v<T, std::filesystem::path>) {
    return value.string() + "x";
  } else if constexpr (IsFixedVector<T>::value) {
    T moved = value;
    moved.x() += static_cast<typename T::Scalar>(0.1);
    return moved;
  } else if constexpr (std::is_floating_point_v<T>) {
    return value > 0 && value < 1 ? value / 2 : value + 1;
  } else {
    return value + 1;
  }
}

// Every field of `Options` inside `base` (a RunSpec, or a scene's Randomization; found by
// `select`), one at a time.
template <typename Options, typename Base, typename Select, typename Check>
int ForEachChange(const Base& base, Select select, Check check) {
  int n = 0;
  for (int index = 0;; ++index) {
    Base spec = base;
    int at = 0;
    std::string name;
    Options::Fields(select(spec), [&](auto& value, const Field& field) {
      if (at++ == index) {
        value = Changed(value, field);
        name = field.Name();
      }
    });
    if (name.empty()) return n;
    check(spec, name);
    ++n;
  }
}

TEST(Schema, ChangingAnyOptionChangesTheRunKey) {
  RunSpec spec = DefaultRunSpec();
  spec.scenes.resize(1);
  const PreparedRun prepared = Prepare(spec);
  const std::vector<SweepView> views = ExpandSweep(spec.sweep);
  const std::string base = RunKey(spec, prepared, views);
  std::set<std::string> keys = {base};
  const auto check = [&](const RunSpec& changed, const std::string& name) {
    const std::string key = RunKey(changed, prepared, views);
    EXPECT_NE(key, base) << name << " is not in the run key";
    EXPECT_TRUE(keys.insert(key).second) << name;
  };
  EXPECT_EQ(ForEachChange<BopOptions>(
                spec, [](RunSpec& s) -> BopOptions& { return s.bop; }, check),
            22);
  EXPECT_EQ(ForEachChange<RenderOptions>(
                spec, [](RunSpec& s) -> RenderOptions& { return s.render; }, check),
            25);
  // Each field of `Options` in `base` changes base's key to one of its own.
  const auto each_field = [&](auto options, const RunSpec& base, auto select) {
    const std::string base_key = RunKey(base, prepared, views);
    return ForEachChange<decltype(options)>(
        base, select, [&](const RunSpec& c, const std::string& name) {
          const std::string key = RunKey(c, prepared, views);
          EXPECT_NE(key, base_key) << name << " is not in the run key";
          EXPECT_TRUE(keys.insert(key).second) << name;
        });
  };
  // The camera's sensor: its image and, with a model other than ideal (an active image sensor),
  // every depth (image sensor) field; inactive, they leave earlier run keys alone.
  {
    EXPECT_EQ(
        each_field(SensorOptions{}, spec, [](RunSpec& s) -> SensorOptions& { return s.sensor; }),
        1);
    EXPECT_EQ(
        each_field(Intrinsics{}, spec, [](RunSpec& s) -> Intrinsics& { return s.intrinsics; }), 6);
    RunSpec kinect = spec;
    kinect.sensor.depth = DepthModel::Defaults(DepthModel::Kind::kKinectV1);
    check(kinect, "camera.depth.model");
    EXPECT_EQ(
        each_field(DepthModel{}, kinect, [](RunSpec& s) -> DepthModel& { return s.sensor.depth; }),
        21);
    RunSpec noisy = spec;
    noisy.sensor.imager.full_well = 5000;
    check(noisy, "camera.imager");
    EXPECT_EQ(each_field(ImageSensor{}, noisy,
                         [](RunSpec& s) -> ImageSensor& { return s.sensor.imager; }),
              4);
    // A rig: each sensor's name, intrinsics, image, pose, and every depth and imager field.
    RunSpec rig = spec;
    rig.rig = {RigSensor{"a", spec.intrinsics, spec.sensor},
               RigSensor{"b", spec.intrinsics, spec.sensor}};
    check(rig, "cameras");
    const auto edited = [&](const char* what, auto edit) {
      RunSpec c = rig;
      edit(c.rig[1]);
      check(c, what);
    };
    edited("cameras[1].name", [](RigSensor& s) { s.name = "c"; });
    EXPECT_EQ(each_field(Intrinsics{}, rig,
                         [](RunSpec& s) -> Intrinsics& { return s.rig[1].intrinsics; }),
              6);
    EXPECT_EQ(each_field(SensorOptions{}, rig,
                         [](RunSpec& s) -> SensorOptions& { return s.rig[1].sensor; }),
              1);
    edited("cameras[1].position", [](RigSensor& s) { s.rig_from_cam.translation().x() = 1e-3; });
    edited("cameras[1].rotation", [](RigSensor& s) {
      s.rig_from_cam.linear() = Eigen::AngleAxisd(1e-6, Eigen::Vector3d::UnitZ()).matrix();
    });
    EXPECT_EQ(each_field(DepthModel{}, rig,
                         [](RunSpec& s) -> DepthModel& { return s.rig[1].sensor.depth; }),
              21);
    EXPECT_EQ(each_field(ImageSensor{}, rig,
                         [](RunSpec& s) -> ImageSensor& { return s.rig[1].sensor.imager; }),
              4);
    // Lens distortion, depth of field and motion blur: each coefficient and field, on the camera
    // and on a rig's camera; inactive, they leave earlier run keys alone.
    RunSpec lensed = spec;
    lensed.intrinsics.distortion.k1 = -0.05;
    lensed.sensor.lens.focal_length_mm = 8;
    lensed.sensor.motion.exposure_s = 0.01;
    lensed.sensor.motion.velocity_mm_s.x() = 100;
    check(lensed, "camera.distortion, lens, motion");
    EXPECT_EQ(each_field(Distortion{}, lensed,
                         [](RunSpec& s) -> Distortion& { return s.intrinsics.distortion; }),
              5);
    EXPECT_EQ(each_field(ThinLens{}, lensed, [](RunSpec& s) -> ThinLens& { return s.sensor.lens; }),
              3);
    EXPECT_EQ(each_field(CameraMotion{}, lensed,
                         [](RunSpec& s) -> CameraMotion& { return s.sensor.motion; }),
              3);
    for (int i = 1; i < 3; ++i) {  // (each_field moves x)
      RunSpec c = lensed;
      c.sensor.motion.angular_velocity_rad_s[i] += 1e-3;
      check(c, "camera.motion.angular_velocity_deg_s");
    }
    edited("cameras[1].distortion", [](RigSensor& s) { s.intrinsics.distortion.p2 = 1e-4; });
    edited("cameras[1].lens", [](RigSensor& s) { s.sensor.lens.focal_length_mm = 12; });
    edited("cameras[1].motion", [](RigSensor& s) {
      s.sensor.motion.exposure_s = 0.01;
      s.sensor.motion.angular_velocity_rad_s.z() = 1;
    });
    // Grasp labels: with grasps on, every field of the gripper, the sampling, the scene filter,
    // the labels and (with a cup) the cup and its sampling.
    RunSpec grasping = spec;
    grasping.grasps.enabled = true;
    grasping.grasps.suction = true;
    check(grasping, "grasps");
    EXPECT_EQ(each_field(ParallelJawGripper{}, grasping,
                         [](RunSpec& s) -> ParallelJawGripper& { return s.grasps.gripper; }),
              9);
    EXPECT_EQ(each_field(AntipodalOptions{}, grasping,
                         [](RunSpec& s) -> AntipodalOptions& { return s.grasps.sampling; }),
              7);
    EXPECT_EQ(each_field(SceneGraspOptions{}, grasping,
                         [](RunSpec& s) -> SceneGraspOptions& { return s.grasps.scene; }),
              1);
    EXPECT_EQ(each_field(GraspLabelOptions{}, grasping,
                         [](RunSpec& s) -> GraspLabelOptions& { return s.grasps.labels; }),
              4);
    EXPECT_EQ(
        each_field(SuctionCup{}, grasping, [](RunSpec& s) -> SuctionCup& { return s.grasps.cup; }),
        9);
    EXPECT_EQ(each_field(SuctionOptions{}, grasping,
                         [](RunSpec& s) -> SuctionOptions& { return s.grasps.suction_sampling; }),
              5);
    RunSpec no_acronym = grasping;
    no_acronym.grasps.acronym = false;
    check(no_acronym, "grasps.formats: acronym");
  }
  // The physically based look: every field of the floor's material (its own, its surface's and
  // its texture's), of a light source and of the environment. The run key reads the bytes of
  // their images: the files exist, and so do those of the changed names.
  {
    testing::ScratchDir dir;
    for (const char* name : {"tile.png", "tile.pngx", "sky.hdr", "sky.hdrx"})
      std::ofstream(dir / name) << name;
    RunSpec pbr = spec;
    pbr.look.floor_material.texture.image = dir / "tile.png";
    pbr.look.environment.image = dir / "sky.hdr";
    check(pbr, "images");
    EXPECT_EQ(
        each_field(Material{}, pbr, [](RunSpec& s) -> Material& { return s.look.floor_material; }),
        2);
    EXPECT_EQ(
        each_field(PrincipledParams{}, pbr,
                   [](RunSpec& s) -> PrincipledParams& { return s.look.floor_material.surface; }),
        8);
    EXPECT_EQ(each_field(Texture{}, pbr,
                         [](RunSpec& s) -> Texture& { return s.look.floor_material.texture; }),
              9);
    EXPECT_EQ(each_field(LightSource{}, pbr,
                         [](RunSpec& s) -> LightSource& { return s.look.light_sources[0]; }),
              12);
    EXPECT_EQ(each_field(Environment{}, pbr,
                         [](RunSpec& s) -> Environment& { return s.look.environment; }),
              8);
    // A material rule, and its material's fields.
    RunSpec changed = spec;
    changed.material_rules.push_back({"*", "", "", Material{}});
    check(changed, "a material rule");
    changed.material_rules.back().material.surface.clearcoat = 0.5f;
    check(changed, "a rule's clear coat");
    changed.material_rules.back().material.surface.multiscatter = true;
    check(changed, "a rule's distribution");
    changed.material_rules.back().material.tangent = Material::Tangent::kModelX;
    check(changed, "a rule's tangent");
  }
  EXPECT_EQ(
      ForEachChange<ArrangementOptions>(
          spec, [](RunSpec& s) -> ArrangementOptions& { return s.scenes[0].arrangement; }, check),
      11);
  // Domain randomisation as the scene resolved it (the run keys the prepared run's): every group
  // set (unset, a group's fields do not reach the key), then every field of each.
  {
    ASSERT_EQ(prepared.randomization.size(), 1u);
    PreparedRun randomized = prepared;
    Randomization& all = randomized.randomization[0];
    all.parts = {PartRandomization{}};
    all.floor = all.fixtures = MaterialRandomization{};
    all.lights = LightRandomization{};
    all.environment = EnvironmentRandomization{};
    all.camera = CameraRandomization{};
    all.distractors = DistractorRandomization{};
    all.distractors->material = MaterialRandomization{};
    const Randomization groups = all;
    const std::string groups_key = RunKey(spec, randomized, views);
    EXPECT_NE(groups_key, base) << "randomize";
    const auto each_draw = [&](auto options, auto select) {
      return ForEachChange<decltype(options)>(
          groups, select, [&](const Randomization& changed, const std::string& name) {
            randomized.randomization[0] = changed;
            const std::string key = RunKey(spec, randomized, views);
            EXPECT_NE(key, groups_key) << name << " is not in the run key";
            EXPECT_TRUE(keys.insert(key).second) << name;
          });
    };
    EXPECT_EQ(each_draw(Randomization{}, [](Randomization& r) -> Randomization& { return r; }), 6);
    EXPECT_EQ(each_draw(PartRandomization{},
                        [](Randomization& r) -> PartRandomization& { return r.parts[0]; }),
              2);
    EXPECT_EQ(
        each_draw(MaterialRandomization{},
                  [](Randomization& r) -> MaterialRandomization& { return r.parts[0].material; }),
        8);
    EXPECT_EQ(each_draw(MaterialRandomization{},
                        [](Randomization& r) -> MaterialRandomization& { return *r.floor; }),
              8);
    EXPECT_EQ(each_draw(MaterialRandomization{},
                        [](Randomization& r) -> MaterialRandomization& { return *r.fixtures; }),
              8);
    EXPECT_EQ(each_draw(LightRandomization{},
                        [](Randomization& r) -> LightRandomization& { return *r.lights; }),
              9);
    EXPECT_EQ(
        each_draw(EnvironmentRandomization{},
                  [](Randomization& r) -> EnvironmentRandomization& { return *r.environment; }),
        3);
    EXPECT_EQ(each_draw(CameraRandomization{},
                        [](Randomization& r) -> CameraRandomization& { return *r.camera; }),
              7);
    EXPECT_EQ(
        each_draw(DistractorRandomization{},
                  [](Randomization& r) -> DistractorRandomization& { return *r.distractors; }),
        3);
    EXPECT_EQ(each_draw(MaterialRandomization{},
                        [](Randomization& r) -> MaterialRandomization& {
                          return *r.distractors->material;
                        }),
              8);
  }
  // The run's own options, the views, and the fast mode's look and light.
  EXPECT_EQ(ForEachChange<RunSpec>(
                spec, [](RunSpec& s) -> RunSpec& { return s; }, check),
            4);
  EXPECT_EQ(ForEachChange<SweepOptions>(
                spec, [](RunSpec& s) -> SweepOptions& { return s.sweep; }, check),
            4);
  EXPECT_EQ(ForEachChange<ViewSampler>(
                spec, [](RunSpec& s) -> ViewSampler& { return s.sampler; }, check),
            9);
  EXPECT_EQ(ForEachChange<Scene>(
                spec, [](RunSpec& s) -> Scene& { return s.look; }, check),
            6);
  EXPECT_EQ(ForEachChange<Scene::Light>(
                spec, [](RunSpec& s) -> Scene::Light& { return s.look.lights[0]; }, check),
            4);
  // A pile: its container, the container's physics, the parts' (both ends of a range) and a
  // rule's.
  {
    RunSpec pile = spec;
    pile.scenes[0].arrangement.layout = Layout::kPile;
    check(pile, "scene.layout: pile");
    EXPECT_EQ(
        each_field(Container{}, pile,
                   [](RunSpec& s) -> Container& { return s.scenes[0].arrangement.container; }),
        6);
    EXPECT_EQ(each_field(PhysicsMaterial{}, pile,
                         [](RunSpec& s) -> PhysicsMaterial& {
                           return s.scenes[0].arrangement.container.material;
                         }),
              3);
    EXPECT_EQ(each_field(PhysicsMaterial{}, pile,
                         [](RunSpec& s) -> PhysicsMaterial& {
                           return s.scenes[0].arrangement.physics.low;
                         }),
              3);
    EXPECT_EQ(each_field(PhysicsMaterial{}, pile,
                         [](RunSpec& s) -> PhysicsMaterial& {
                           return s.scenes[0].arrangement.physics.high;
                         }),
              3);
    RunSpec changed = pile;
    changed.scenes[0].container_color.x() = 0.9f;
    check(changed, "scene.container.color");
    changed = pile;
    changed.scenes[0].container_material = Material{};
    check(changed, "scene.container.material");
    RunSpec ruled = pile;
    ruled.scenes[0].physics_rules.push_back({"*", "", "", PhysicsDraw{}, ""});
    check(ruled, "scene.physics[0]");
    EXPECT_EQ(each_field(PhysicsMaterial{}, ruled,
                         [](RunSpec& s) -> PhysicsMaterial& {
                           return s.scenes[0].physics_rules[0].physics.low;
                         }),
              3);
    EXPECT_EQ(each_field(PhysicsMaterial{}, ruled,
                         [](RunSpec& s) -> PhysicsMaterial& {
                           return s.scenes[0].physics_rules[0].physics.high;
                         }),
              3);
  }
}

// The scene keys, read from a recipe with parts (a scene section needs them).
TEST(Schema, EverySceneKeyIsRead) {
  RunSpec base;
  base.scenes.resize(1);
  base.scenes[0].arrangement.layout = Layout::kRow;  // copies and poses apply
  const int n = ForEachChange<ArrangementOptions>(
      base, [](RunSpec& s) -> ArrangementOptions& { return s.scenes[0].arrangement; },
      [&](const RunSpec& changed, const std::string& name) {
        std::string text = "parts:\n  - {family: hex_nut}\nscene:\n";
        ArrangementOptions::Fields(
            changed.scenes[0].arrangement, [&](const auto& value, const Field& field) {
              text += "  " + std::string(field.key) + ": " + FieldText(value, field) +
                      (field.kind == "length" ? " mm" : "") + "\n";
            });
        const RunSpec parsed = ParseRecipe(text, "r.yaml", ".");
        ASSERT_EQ(parsed.scenes.size(), 1u) << name;
        std::string got, want;
        const auto all = [](const ArrangementOptions& a, std::string* out) {
          ArrangementOptions::Fields(a, [&](const auto& value, const Field& field) {
            *out += std::string(field.key) + "=" + FieldText(value, field) + ";";
          });
        };
        all(parsed.scenes[0].arrangement, &got);
        all(changed.scenes[0].arrangement, &want);
        EXPECT_EQ(got, want) << name;
      });
  // layout, pose, gap, copies, radius, seed, drop_height, settle_time, time_step, confirm_rest,
  // out_of_container
  EXPECT_EQ(n, 11);
}

TEST(Schema, EveryOutputOptionSurvivesTheShardFile) {
  const auto text = [](const BopOptions& b) {
    std::string all;
    BopOptions::Fields(b, [&](const auto& value, const Field& field) {
      all += std::string(field.Name()) + "=" + FieldText(value, field) + ";";
    });
    return all;
  };
  ForEachChange<BopOptions>(
      RunSpec{}, [](RunSpec& s) -> BopOptions& { return s.bop; },
      [&](const RunSpec& changed, const std::string& name) {
        EXPECT_EQ(text(OutputOptionsFromJson(OutputOptionsJson(changed.bop))), text(changed.bop))
            << name;
      });
  EXPECT_THROW(OutputOptionsFromJson("{\"depth_scale\": 0.1}"), Error);  // the rest is missing
}

// Each option with a recipe key is read from it: the recipe that writes the changed value (as
// the reference prints it) gives the changed options.
TEST(Schema, EveryRecipeKeyIsRead) {
  // An image for an image environment.
  testing::ScratchDir dir;
  testing::WriteSolidPng(dir / "sky.png", 2, 2, 0x40);
  int read = 0;
  // Each field of the options `select` finds in `base` (or only the one keyed `only`), written
  // as "KEY: VALUE" in place of the {} of `recipe(key)` (the recipe text the key needs).
  const auto read_in = [&](auto recipe, const RunSpec& base, auto select,
                           std::string_view only = {}) {
    using Options = std::decay_t<decltype(select(std::declval<RunSpec&>()))>;
    ForEachChange<Options>(base, select, [&](const RunSpec& changed, const std::string&) {
      Options::Fields(
          select(const_cast<RunSpec&>(changed)), [&](const auto& value, const Field& field) {
            using T = std::decay_t<decltype(value)>;
            if (field.key.empty() || field.by_hand || (!only.empty() && field.key != only)) return;
            if constexpr (IsOptional<T>::value) {
              if (!value) return;  // unset: nothing to write
            }
            T expected = value;
            const std::string text = RecipeText(value, field);
            std::string yaml = recipe(field.key);
            yaml.replace(yaml.find("{}"), 2, std::string(field.key) + ": " + text);
            const RunSpec parsed = ParseRecipe(yaml, "r.yaml", dir.path());
            Options::Fields(select(const_cast<RunSpec&>(parsed)),
                            [&](const auto& got, const Field& other) {
                              if constexpr (std::is_same_v<std::decay_t<decltype(got)>, T>) {
                                if (other.Name() != field.Name()) return;
                                if constexpr (IsFixedVector<T>::value) {  // degrees: to 1e-12
                                  EXPECT_LT((got - expected).norm(), 1e-12) << yaml;
                                } else {
                                  EXPECT_EQ(got, expected) << yaml;
                                }
                              }
                            });
            ++read;
          });
    });
  };
  // The recipe text of the section at its path ("grasps.gripper": nested) with {} for its key.
  const auto nested = [](const char* name) {
    std::string yaml, indent;
    std::string path = name;
    for (size_t dot; (dot = path.find('.')) != std::string::npos; indent += "  ") {
      yaml += indent + path.substr(0, dot) + ":\n";
      path = path.substr(dot + 1);
    }
    return yaml + indent + path + ":\n" + indent + "  {}\n";
  };
  // The same after `prefix(key)`, what the key needs of the rest of the recipe.
  const auto section_after = [&](const char* name, auto prefix, auto select) {
    read_in([&](std::string_view key) { return prefix(key) + nested(name); }, RunSpec{}, select);
  };
  const auto section = [&](const char* name, auto select, std::string_view only = {}) {
    const std::string yaml = nested(name);
    read_in([&](std::string_view) { return yaml; }, RunSpec{}, select, only);
  };
  section("output", [](RunSpec& s) -> BopOptions& { return s.bop; });
  section("render", [](RunSpec& s) -> RenderOptions& { return s.render; });
  section("tessellation", [](RunSpec& s) -> TessellationOptions& { return s.tessellation; });
  section("limits", [](RunSpec& s) -> RunLimits& { return s.limits; });
  section("grasps.gripper", [](RunSpec& s) -> ParallelJawGripper& { return s.grasps.gripper; });
  section("grasps", [](RunSpec& s) -> AntipodalOptions& { return s.grasps.sampling; });
  section("grasps", [](RunSpec& s) -> SceneGraspOptions& { return s.grasps.scene; });
  section("grasps", [](RunSpec& s) -> GraspLabelOptions& { return s.grasps.labels; });
  section("grasps.suction", [](RunSpec& s) -> SuctionCup& { return s.grasps.cup; });
  section("grasps.suction",
          [](RunSpec& s) -> SuctionOptions& { return s.grasps.suction_sampling; });
  section("materials.floor",
          [](RunSpec& s) -> PrincipledParams& { return s.look.floor_material.surface; });
  section("materials.floor", [](RunSpec& s) -> Material& { return s.look.floor_material; });
  // Randomisation groups (set when selected): they draw in the pbr mode, the camera's lens and
  // noise need a lens and noise, an environment's rotation an image environment.
  const auto pbr = [](std::string_view) { return std::string("render: {mode: pbr}\n"); };
  section_after("randomize.floor", pbr, [](RunSpec& s) -> MaterialRandomization& {
    auto& floor = s.randomize.draws.floor;
    return floor ? *floor : floor.emplace();
  });
  section_after("randomize.lights", pbr, [](RunSpec& s) -> LightRandomization& {
    auto& lights = s.randomize.draws.lights;
    return lights ? *lights : lights.emplace();
  });
  section_after(
      "randomize.environment",
      [](std::string_view key) {
        return std::string("render: {mode: pbr}\n") +
               (key == "rotation" ? "lighting: {environment: {type: image, file: sky.png}}\n" : "");
      },
      [](RunSpec& s) -> EnvironmentRandomization& {
        auto& environment = s.randomize.draws.environment;
        return environment ? *environment : environment.emplace();
      });
  section_after(
      "randomize.camera",
      [](std::string_view) {
        return std::string(
            "render: {mode: pbr}\ncamera: {imager: {full_well: 10000}, lens: {focal_length: 8}}\n");
      },
      [](RunSpec& s) -> CameraRandomization& {
        auto& camera = s.randomize.draws.camera;
        return camera ? *camera : camera.emplace();
      });
  section_after("randomize.distractors", pbr, [](RunSpec& s) -> DistractorRandomization& {
    auto& distractors = s.randomize.draws.distractors;
    return distractors ? *distractors : distractors.emplace();
  });
  section_after("randomize.distractors.material", pbr, [](RunSpec& s) -> MaterialRandomization& {
    auto& distractors = s.randomize.draws.distractors;
    auto& material = (distractors ? *distractors : distractors.emplace()).material;
    return material ? *material : material.emplace();
  });
  // A recipe text that is the same for every key.
  const auto fixed = [](const std::string& yaml) {
    return [yaml](std::string_view) { return yaml; };
  };
  section("camera", [](RunSpec& s) -> Intrinsics& { return s.intrinsics; });
  section("render", [](RunSpec& s) -> Scene& { return s.look; });
  // RunSpec's own options, each in its own section.
  const auto run = [](RunSpec& s) -> RunSpec& { return s; };
  section("tessellation", run, "crease_angle");
  section("classes", run, "by");
  section("sweep", run, "min_visible_pixels");
  section("render", run, "colors");
  // The views, the camera's image and its motion (pbr only; the exposure is required).
  section("sweep", [](RunSpec& s) -> SweepOptions& { return s.sweep; });
  section("sweep", [](RunSpec& s) -> ViewSampler& { return s.sampler; });
  section("camera", [](RunSpec& s) -> SensorOptions& { return s.sensor; });
  const auto motion = [](RunSpec& s) -> CameraMotion& { return s.sensor.motion; };
  const std::string moving = "render: {mode: pbr}\ncamera:\n  motion:\n";
  read_in(fixed(moving + "    {}\n"), RunSpec{}, motion, "exposure_ms");
  for (const char* key : {"velocity_mm_s", "angular_velocity_deg_s"})
    read_in(fixed(moving + "    exposure_ms: 5\n    {}\n"), RunSpec{}, motion, key);
  // A fast-mode light gives a direction or a position.
  const auto light = [](RunSpec& s) -> Scene::Light& { return s.look.lights[0]; };
  read_in(fixed("render:\n  lights:\n    - {}\n"), RunSpec{}, light, "direction");
  read_in(fixed("render:\n  lights:\n    - {}\n"), RunSpec{}, light, "position");
  read_in(fixed("render:\n  lights:\n    - position: [0, 0, 1000]\n      {}\n"), RunSpec{}, light,
          "intensity");
  // A pile's container, its physics and the parts'.
  RunSpec pile;
  pile.scenes.resize(1);
  const std::string scene = "parts:\n  - {family: hex_nut}\nscene:\n  layout: pile\n";
  const std::string container = scene + "  container:\n    type: tote\n    {}\n";
  read_in(fixed(container), pile,
          [](RunSpec& s) -> Container& { return s.scenes[0].arrangement.container; });
  read_in(fixed(container), pile, [](RunSpec& s) -> PhysicsMaterial& {
    return s.scenes[0].arrangement.container.material;
  });
  read_in(fixed(scene + "  physics:\n    {}\n"), pile,
          [](RunSpec& s) -> PhysicsMaterial& { return s.scenes[0].arrangement.physics.low; });
  EXPECT_GT(read, 130);
}

// `cadsynth generate --help-recipe` and docs/recipes.md list every recipe key of the described
// sections.
TEST(Schema, ReferenceAndReadmeListEveryKey) {
  const std::string reference = RecipeReference();
  std::ifstream in(std::string(CADSYNTH_SOURCE_DIR) + "/docs/recipes.md");
  std::stringstream readme;
  readme << in.rdbuf();
  const auto expect_key = [&](const std::string& section, const Field& field) {
    if (field.key.empty()) return;
    const std::string line = "  " + std::string(field.key) + ":";
    EXPECT_NE(SchemaAt(section).Find(field.key), nullptr) << section << "." << field.key;
    EXPECT_NE(reference.find(line), std::string::npos) << section << "." << field.key;
    // docs/recipes.md's recipe example lists it, set or commented out.
    EXPECT_TRUE(readme.str().find(line) != std::string::npos ||
                readme.str().find("  # " + std::string(field.key) + ":") != std::string::npos)
        << "docs/recipes.md lacks " << section << "." << field.key;
  };
  const BopOptions bop;
  const RenderOptions render;
  BopOptions::Fields(bop, [&](const auto&, const Field& f) { expect_key("output", f); });
  RenderOptions::Fields(render, [&](const auto&, const Field& f) { expect_key("render", f); });
  const TessellationOptions tessellation;
  TessellationOptions::Fields(tessellation,
                              [&](const auto&, const Field& f) { expect_key("tessellation", f); });
  const ArrangementOptions arrangement;
  ArrangementOptions::Fields(arrangement,
                             [&](const auto&, const Field& f) { expect_key("scene", f); });
  const RunLimits limits;
  RunLimits::Fields(limits, [&](const auto&, const Field& f) { expect_key("limits", f); });
  const DepthModel depth;
  DepthModel::Fields(depth, [&](const auto&, const Field& f) { expect_key("camera.depth", f); });
  const ImageSensor imager;
  ImageSensor::Fields(imager, [&](const auto&, const Field& f) { expect_key("camera.imager", f); });
  const Distortion distortion;
  Distortion::Fields(distortion,
                     [&](const auto&, const Field& f) { expect_key("camera.distortion", f); });
  const ThinLens lens;
  ThinLens::Fields(lens, [&](const auto&, const Field& f) { expect_key("camera.lens", f); });
  const Material material;
  PrincipledParams::Fields(material.surface,
                           [&](const auto&, const Field& f) { expect_key("materials.floor", f); });
  Material::Fields(material,
                   [&](const auto&, const Field& f) { expect_key("materials.floor", f); });
  Texture::Fields(material.texture,
                  [&](const auto&, const Field& f) { expect_key("materials.floor.texture", f); });
  const LightSource light;
  LightSource::Fields(light,
                      [&](const auto&, const Field& f) { expect_key("lighting.lights[]", f); });
  const Environment environment;
  Environment::Fields(environment,
                      [&](const auto&, const Field& f) { expect_key("lighting.environment", f); });
  const Randomization randomize;
  Randomization::Fields(randomize,
                        [&](const auto&, const Field& f) { expect_key("randomize", f); });
  const PartRandomization part;
  PartRandomization::Fields(
      part, [&](const auto&, const Field& f) { expect_key("randomize.parts[]", f); });
  for (const char* section : {"randomize.parts[]", "randomize.floor", "randomize.fixtures",
                              "randomize.distractors.material"}) {
    MaterialRandomization::Fields(part.material,
                                  [&](const auto&, const Field& f) { expect_key(section, f); });
  }
  const LightRandomization lights;
  LightRandomization::Fields(
      lights, [&](const auto&, const Field& f) { expect_key("randomize.lights", f); });
  const EnvironmentRandomization world;
  EnvironmentRandomization::Fields(
      world, [&](const auto&, const Field& f) { expect_key("randomize.environment", f); });
  const CameraRandomization camera;
  CameraRandomization::Fields(
      camera, [&](const auto&, const Field& f) { expect_key("randomize.camera", f); });
  const DistractorRandomization distractors;
  DistractorRandomization::Fields(
      distractors, [&](const auto&, const Field& f) { expect_key("randomize.distractors", f); });
  const Intrinsics intrinsics;
  Intrinsics::Fields(intrinsics, [&](const auto&, const Field& f) { expect_key("camera", f); });
  const SensorOptions sensor;
  SensorOptions::Fields(sensor, [&](const auto&, const Field& f) { expect_key("camera", f); });
  CameraMotion::Fields(sensor.motion,
                       [&](const auto&, const Field& f) { expect_key("camera.motion", f); });
  const SweepOptions sweep;
  SweepOptions::Fields(sweep, [&](const auto&, const Field& f) { expect_key("sweep", f); });
  const ViewSampler sampler;
  ViewSampler::Fields(sampler, [&](const auto&, const Field& f) { expect_key("sweep", f); });
  const Scene look;
  Scene::Fields(look, [&](const auto&, const Field& f) { expect_key("render", f); });
  Scene::Light::Fields(look.lights[0],
                       [&](const auto&, const Field& f) { expect_key("render.lights[]", f); });
  const Container container;
  Container::Fields(container,
                    [&](const auto&, const Field& f) { expect_key("scene.container", f); });
  PhysicsMaterial::Fields(container.material, [&](const auto&, const Field& f) {
    expect_key("scene.container", f);
    expect_key("scene.physics", f);
  });
  // RunSpec's own options, each in its section.
  const std::map<std::string_view, std::string> sections = {{"crease_angle", "tessellation"},
                                                            {"by", "classes"},
                                                            {"min_visible_pixels", "sweep"},
                                                            {"colors", "render"}};
  const RunSpec spec;
  RunSpec::Fields(spec, [&](const auto&, const Field& f) { expect_key(sections.at(f.key), f); });
}

// Each camera.depth key is read over the model's defaults.
TEST(Schema, EveryDepthKeyIsRead) {
  RunSpec base;
  base.sensor.depth = DepthModel::Defaults(DepthModel::Kind::kKinectV1);
  base.sensor.depth.max_incidence_rad = 0.5;  // changed: halved (adding 1 rad passes 90 degrees)
  const int n = ForEachChange<DepthModel>(
      base, [](RunSpec& s) -> DepthModel& { return s.sensor.depth; },
      [&](const RunSpec& changed, const std::string& name) {
        const DepthModel& want = changed.sensor.depth;
        std::string text = "camera:\n  depth:\n";
        DepthModel::Fields(want, [&](const auto& value, const Field& field) {
          text += "    " + std::string(field.key) + ": " + FieldText(value, field) +
                  (field.kind == "length"  ? " mm"
                   : field.kind == "angle" ? " rad"
                                           : "") +
                  "\n";
        });
        if (want.kind != DepthModel::Kind::kKinectV1) return;  // another model's keys differ
        const RunSpec parsed = ParseRecipe(text, "r.yaml", ".");
        std::string got, expected;
        const auto all = [](const DepthModel& m, std::string* out) {
          DepthModel::Fields(m, [&](const auto& value, const Field& field) {
            *out += std::string(field.key) + "=" + FieldText(value, field) + ";";
          });
        };
        all(parsed.sensor.depth, &got);
        all(want, &expected);
        EXPECT_EQ(got, expected) << name;
      });
  EXPECT_EQ(n, 21);
}

}  // namespace
}  // namespace cadsynth
