#include "tools/pipeline/journal.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <system_error>

#include "cad/core/error.h"
#include "cad/part_cache.h"
#include "dataset/file_io.h"
#include "render/renderer.h"

namespace cadsynth {

const std::string& BuildId() {
  static const std::string id = [] {
    try {
      const std::string bytes = ReadFileText("/proc/self/exe");
      std::ostringstream out;
      out << bytes.size() << "-" << std::hex << Crc32(bytes);
      return out.str();
    } catch (const Error&) {
      return std::string("unknown");
    }
  }();
  return id;
}

namespace {

// The run key as it is written: the stream, the images the look reads (their bytes go in last)
// and the described options by name (cad/core/schema.h).
struct KeyWriter {
  std::ostringstream key;
  std::set<std::filesystem::path> images;

  KeyWriter() { key.precision(17); }

  template <class Options>
  void Fields(std::string_view section, const Options& options) {
    key << section;
    Options::Fields(options, [this](const auto& value, const Field& field) {
      key << " " << field.Name() << "=" << FieldText(value, field);
    });
    key << "\n";
  }

  // A material's own fields, its surface's and its texture's; the texture's image is read.
  void Material(const std::string& what, const cadsynth::Material& m) {
    Fields(what, m);
    Fields(what + ".surface", m.surface);
    Fields(what + ".texture", m.texture);
    if (!m.texture.image.empty()) images.insert(m.texture.image);
  }

  // A material's randomisation: its described fields, and the textures of its folder (their
  // files and tile size; the images are read).
  void Randomized(const std::string& what, const MaterialRandomization& m) {
    Fields(what, m);
    if (m.textures.empty()) return;
    key << what << ".textures";
    for (const Texture& t : m.textures) {
      key << " " << t.image.string() << " " << FieldText(t.scale_mm, Field{});
      images.insert(t.image);
    }
    key << "\n";
  }

  void ImageChoice(const char* what, const cadsynth::ImageChoice& c) {
    key << what;
    for (const std::filesystem::path& file : c.files) {
      key << " " << file.string();
      images.insert(file);
    }
    key << "\n";
  }
};

// The bytes of every CAD file, not only its name: a file edited between a kill and the rerun
// (or between two shards) would otherwise mix frames of two geometries.
void KeyInputFiles(const RunSpec& spec, KeyWriter& w) {
  std::set<std::filesystem::path> files;
  for (const SceneSpec& scene : spec.scenes) {
    for (const PartSource& source : scene.sources) {
      if (source.kind == PartSource::Kind::kFile) files.insert(source.path);
      // A family made from a file (scaled, from_file): that file's bytes too.
      for (const ParamValues& values : source.variants) {
        const auto it = values.find("file");
        if (it == values.end()) continue;
        const std::string* path = std::get_if<std::string>(&it->second);
        if (path != nullptr && !path->empty()) files.insert(*path);
      }
    }
    if (scene.container_file) files.insert(scene.container_file->path);
  }
  for (const std::filesystem::path& file : files) {
    const std::string bytes = ReadFileText(file);
    w.key << "file " << file.string() << " " << bytes.size() << " " << Crc32(bytes) << "\n";
  }
}

// Lens distortion, depth of field and motion blur (recipes without them keep their run keys).
void KeyOptics(const Intrinsics& k, const SensorOptions& sensor, KeyWriter& w) {
  if (k.distortion.active()) w.Fields("distortion", k.distortion);
  if (sensor.lens.active()) w.Fields("lens", sensor.lens);
  if (sensor.motion.active()) w.Fields("motion", sensor.motion);
}

void KeySensors(const RunSpec& spec, KeyWriter& w) {
  w.Fields("camera", spec.intrinsics);
  // The sensor's image and depth model (written only when either is set, as before).
  if (spec.sensor.image != SensorOptions::Image::kRgb ||
      spec.sensor.depth.kind != DepthModel::Kind::kIdeal) {
    w.Fields("sensor", spec.sensor);  // the image
    w.Fields("depth", spec.sensor.depth);
  }
  if (spec.sensor.imager.active()) w.Fields("imager", spec.sensor.imager);
  KeyOptics(spec.intrinsics, spec.sensor, w);
  // A rig's sensors (recipes without `cameras:` keep their earlier run keys).
  for (const RigSensor& sensor : spec.rig) {
    const Eigen::Matrix<double, 3, 4> pose = sensor.rig_from_cam.matrix().topRows<3>();
    w.key << "rig_sensor " << sensor.name << " pose";
    for (int i = 0; i < 12; ++i) w.key << " " << pose(i % 3, i / 3);
    w.key << "\n";
    w.Fields("sensor", sensor.sensor);
    w.Fields("camera", sensor.intrinsics);
    w.Fields("depth", sensor.sensor.depth);
    w.Fields("imager", sensor.sensor.imager);
    KeyOptics(sensor.intrinsics, sensor.sensor, w);
  }
}

// Each scene's arrangement, and a pile's container and physics.
void KeyScenes(const RunSpec& spec, KeyWriter& w) {
  for (const SceneSpec& scene : spec.scenes) {
    w.Fields("scene", scene.arrangement);
    // (Recipes without a pick sequence keep their run keys.)
    if (scene.arrangement.sequence.picks > 0) w.Fields("sequence", scene.arrangement.sequence);
    if (scene.arrangement.layout != Layout::kPile && scene.arrangement.pose != PoseMode::kDropped)
      continue;
    const Container& c = scene.arrangement.container;
    w.Fields("container", c);
    w.Fields("container.material", c.material);
    w.key << "container_look " << FieldText(scene.container_color, Field{}) << " "
          << scene.container_material.has_value() << "\n";
    // The parts' physics, both ends of its ranges (equal where a value is fixed), and the rules.
    w.Fields("physics.low", scene.arrangement.physics.low);
    w.Fields("physics.high", scene.arrangement.physics.high);
    for (const PhysicsRule& rule : scene.physics_rules) {
      w.key << "physics_rule '" << rule.name << "' '" << rule.family << "' '" << rule.file << "'\n";
      w.Fields("physics_rule.low", rule.physics.low);
      w.Fields("physics_rule.high", rule.physics.high);
    }
  }
}

// The rest of the spec that changes parts, classes or pixels without changing the recipe text
// (a RunSpec built in code has none): meshes' crease angle, classes, colours, the look; in the
// physically based mode materials, light sources and the environment.
void KeyLook(const RunSpec& spec, KeyWriter& w) {
  w.Fields("run", spec);  // RunSpec's own options: crease angle, classes, views, colours
  for (const auto& [name, globs] : spec.class_groups) {
    w.key << "class " << name;
    for (const std::string& glob : globs) w.key << " " << glob;
    w.key << "\n";
  }
  const Scene& look = spec.look;
  w.Fields("look", look);  // the look options only (Scene::Fields)
  for (const Scene::Light& light : look.lights) w.Fields("light", light);
  w.Material("floor_material", look.floor_material);
  if (spec.default_material) w.Material("default_material", *spec.default_material);
  for (const MaterialRule& rule : spec.material_rules) {
    w.key << "rule " << rule.name << " | " << rule.family << " | " << rule.file << "\n";
    w.Material("material", rule.material);
  }
  for (const LightSource& l : look.light_sources) w.Fields("light_source", l);
  const Environment& env = look.environment;
  w.Fields("environment", env);
  if (!env.image.empty()) w.images.insert(env.image);
}

// Domain randomisation, as each scene resolved it (a RunSpec built in code too), and the images
// its texture folders hold (a file added to a folder moves the picks).
void KeyRandomization(const Randomization& r, KeyWriter& w) {
  w.Fields("randomize", r);
  for (const PartRandomization& p : r.parts) {
    w.Fields("randomize_part", p);
    w.Randomized("randomize_part.material", p.material);
  }
  // Resolved by the run: the rule that draws each instance's material.
  w.key << "randomize_instance_rules";
  for (int rule : r.instance_rule) w.key << " " << rule;
  w.key << "\n";
  if (r.floor) w.Randomized("randomize_floor", *r.floor);
  if (r.fixtures) w.Randomized("randomize_fixtures", *r.fixtures);
  if (r.lights) w.Fields("randomize_lights", *r.lights);
  if (r.background) w.ImageChoice("randomize_background", r.background->images);
  if (const auto& e = r.environment) {
    if (e->images) w.ImageChoice("randomize_environment_images", *e->images);
    w.Fields("randomize_environment", *e);
  }
  if (const auto& d = r.distractors) {
    w.Fields("randomize_distractors", *d);
    w.key << "randomize_first_distractor " << r.first_distractor << "\n";  // resolved by the run
    if (d->material) w.Randomized("randomize_distractor_material", *d->material);
  }
  if (r.camera) w.Fields("randomize_camera", *r.camera);
}

// What prepare made of the recipe, whatever option decided it (a RunSpec built in code can
// change a scene's arrangement or a part without changing the recipe text): every object's
// geometry and colour, and every instance's pose.
void KeyPrepared(const PreparedRun& prepared, KeyWriter& w) {
  for (const Part& part : prepared.parts) {
    w.key << "object " << part.name << " " << KeyHasher().Geometry(part.mesh).Key().Hex() << " "
          << part.color.value_or(Eigen::Vector3f::Constant(-1)).transpose() << "\n";
  }
  for (const Scene& scene : prepared.scenes) {
    w.key << "scene\n";
    for (const Instance& instance : scene.instances) {
      w.key << instance.part << " " << instance.world_from_model.matrix().reshaped().transpose()
            << " " << instance.color.value_or(Eigen::Vector3f::Constant(-1)).transpose() << "\n";
    }
    for (const Eigen::Vector3f& color : scene.part_colors) w.key << color.transpose() << " ";
    w.key << "\n";
    // Totes, containers from files and distractors: where they are and how they look.
    for (const Scene::Fixture& f : scene.fixtures) {
      w.key << "fixture " << f.name << " " << KeyHasher().Geometry(f.mesh).Key().Hex() << " "
            << f.color.transpose() << "\n";
      w.Material("fixture_material", f.material);
    }
  }
}

void KeyGrasps(const GraspSpec& grasps, KeyWriter& w) {
  if (!grasps.enabled) return;
  w.Fields("gripper", grasps.gripper);
  w.Fields("grasp_sampling", grasps.sampling);
  w.Fields("grasp_scene", grasps.scene);
  w.Fields("grasp_labels", grasps.labels);
  w.key << "acronym " << grasps.acronym << "\n";
  if (grasps.suction) {
    w.Fields("cup", grasps.cup);
    w.Fields("suction_sampling", grasps.suction_sampling);
  }
}

}  // namespace

std::string RunKey(const RunSpec& spec, const PreparedRun& prepared,
                   const std::vector<SweepView>& views) {
  KeyWriter w;
  w.key << "cadsynth run key 2\n";
  // The recipe as it was read (not read again: it may have changed, or be a pipe).
  if (!spec.recipe.empty()) w.key << "recipe\n" << spec.recipe_text << "\n";
  if (spec.reseed != 0)
    w.key << "reseed " << spec.reseed << "\n";  // the seeds differ from the text
  KeyInputFiles(spec, w);
  w.key << prepared.variants_json << "\n";
  KeySensors(spec, w);
  w.Fields("output", spec.bop);
  w.Fields("render", spec.render);
  w.Fields("tessellation", spec.tessellation);
  w.Fields("collision", spec.collision);
  KeyScenes(spec, w);
  w.Fields("limits", spec.limits);
  w.Fields("sweep", spec.sweep);
  w.Fields("sampler", spec.sampler);
  KeyLook(spec, w);
  for (const Randomization& r : prepared.randomization) KeyRandomization(r, w);
  KeyPrepared(prepared, w);
  KeyGrasps(spec.grasps, w);
  // The bytes of every image a material above reads.
  for (const std::filesystem::path& image : w.images) {
    const std::string bytes = ReadFileText(image);
    w.key << "image " << image.string() << " " << bytes.size() << " " << Crc32(bytes) << "\n";
  }
  for (const SweepView& v : views)
    w.key << v.world_from_cam.matrix().reshaped().transpose() << "\n";
  // Embree's kernels on this machine: different widths give different last bits.
  w.key << "trace " << TracingIsa(spec.render.isa) << "\n";
  // This build of cadsynth (our libraries are linked in statically): another build may write
  // other bytes, so it neither resumes this run nor joins its shards.
  w.key << "build " << BuildId() << "\n";
  return w.key.str();
}

RunLock::RunLock(const std::filesystem::path& staging) : path_(staging.string() + ".lock") {
  fd_ = ::open(path_.c_str(), O_CREAT | O_RDWR, 0644);
  if (fd_ < 0) throw Error(path_ + ": cannot create lock file: " + std::strerror(errno));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd_);
    throw Error(staging.string() + ": another cadsynth run is writing this dataset");
  }
}

void RunLock::Release() {
  if (fd_ < 0) return;
  std::error_code ec;
  std::filesystem::remove(path_, ec);
  ::close(fd_);
  fd_ = -1;
}

void MarkDataset(const std::filesystem::path& folder) {
  // Shards starting together all mark the same folder: a temporary name of this process each,
  // then a rename (the same bytes win whichever comes last).
  const std::filesystem::path marker = folder / kDatasetMarker;
  std::error_code ec;
  if (std::filesystem::exists(marker, ec)) return;
  const std::filesystem::path temporary = marker.string() + ".tmp." + std::to_string(::getpid());
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out << "A dataset written by cadsynth: 'cadsynth generate --overwrite' may replace this "
           "folder.\n";
    if (!out) throw Error(marker.string() + ": cannot write the dataset marker");
  }
  std::filesystem::rename(temporary, marker, ec);
  if (ec) {
    std::filesystem::remove(temporary, ec);
    throw Error(marker.string() + ": cannot write the dataset marker");
  }
}

void CheckReplaceable(const std::filesystem::path& output,
                      const std::vector<std::filesystem::path>& inputs) {
  std::error_code ec;
  if (!std::filesystem::exists(output, ec)) return;
  const std::string name = output.string();
  if (!std::filesystem::is_directory(output, ec))
    throw Error(name + ": exists and is not a folder: --overwrite replaces only datasets");
  if (!std::filesystem::exists(output / kDatasetMarker, ec) &&
      !std::filesystem::exists(output / "variants.json", ec) &&
      !std::filesystem::is_empty(output, ec)) {
    throw Error(name + ": not a dataset written by cadsynth (no " + kDatasetMarker +
                "): --overwrite would delete it; remove it yourself or write elsewhere");
  }
  if (std::filesystem::exists(output / ".shards", ec)) {
    throw Error(name + ": holds shards of a run (" + name +
                "/.shards): merge them or remove the folder yourself; --overwrite would delete "
                "frames shards may still be writing");
  }
  const std::filesystem::path root = std::filesystem::weakly_canonical(output, ec);
  for (const std::filesystem::path& input : inputs) {
    if (input.empty()) continue;
    const std::filesystem::path file = std::filesystem::weakly_canonical(input, ec);
    const auto mismatch = std::mismatch(root.begin(), root.end(), file.begin(), file.end());
    if (mismatch.first == root.end()) {
      throw Error(name + ": holds " + input.string() +
                  ", an input of this run: --overwrite would delete it");
    }
  }
}

StagingRun::StagingRun(const std::filesystem::path& output, const std::string& run_key,
                       const std::function<void(const std::string&)>& info) {
  std::error_code ec;
  std::filesystem::create_directories(output.parent_path(), ec);
  if (ec) throw Error(output.parent_path().string() + ": cannot create folder: " + ec.message());
  std::string name = ".";
  name += output.filename().string();
  name += ".partial";
  root_ = output.parent_path() / name;
  lock_ = std::make_unique<RunLock>(root_);
  const std::filesystem::path key_path = root_ / ".run_key";
  std::ifstream in(key_path);
  std::stringstream old_key;
  old_key << in.rdbuf();
  if (old_key.str() != run_key) {
    if (std::filesystem::exists(root_, ec) && info) {
      info("starting over: " + root_.string() + " holds an interrupted run of something else");
    }
    std::filesystem::remove_all(root_, ec);
    CreateFolder(root_);
    MarkDataset(root_);
    WriteFileAtomic(key_path, run_key);
  } else if (info) {
    info("resuming the interrupted run in " + root_.string());
  }
}

StagingRun::~StagingRun() = default;

void StagingRun::Publish(const std::filesystem::path& output, bool overwrite,
                         const std::vector<std::filesystem::path>& inputs) {
  std::error_code ec;
  const bool replace = std::filesystem::exists(output, ec);
  // Refused before anything changes: the staging folder stays resumable.
  if (replace && !overwrite)
    throw Error(output.string() + ": already exists (pass --overwrite to replace it)");
  if (replace) CheckReplaceable(output, inputs);
  std::filesystem::remove(root_ / ".run_key", ec);
  if (replace) {
    std::filesystem::path old = output;
    old += ".old-" + std::to_string(::getpid());
    std::filesystem::rename(output, old, ec);
    if (ec) throw Error(output.string() + ": cannot move the old dataset aside: " + ec.message());
    std::filesystem::rename(root_, output, ec);
    if (ec) {
      std::error_code restore;
      std::filesystem::rename(old, output, restore);
      throw Error(output.string() + ": cannot move the new dataset into place: " + ec.message());
    }
    std::filesystem::remove_all(old, ec);
  } else {
    std::filesystem::rename(root_, output, ec);
    if (ec) throw Error(output.string() + ": cannot move the dataset into place: " + ec.message());
  }
  lock_->Release();
}

size_t FinishDataset(const std::filesystem::path& root, const BopOptions& options,
                     const std::vector<std::unique_ptr<RigSceneWriter>>& writers,
                     const std::vector<ObjectClass>& classes) {
  if (writers.empty()) return 0;
  std::vector<BopSensor> sensors;
  for (size_t k = 0; k < writers[0]->size(); ++k) sensors.push_back(writers[0]->sensor(k).sensor());
  std::vector<std::vector<SceneSplit>> splits(sensors.size());  // per sensor, per scene
  size_t frames = 0;
  for (const auto& writer : writers) {
    frames += writer->WrittenFrames().size();
    std::vector<SceneSplit> scene = writer->Finish();
    for (size_t k = 0; k < sensors.size(); ++k) splits[k].push_back(std::move(scene[k]));
  }
  // splits/ and test_targets_bop19.json: the first sensor is the rig's evaluation sensor (the
  // image ids, and so the splits, are the same for every sensor).
  WriteSplits(root, splits[0]);
  for (size_t k = 0; k < sensors.size(); ++k)
    WriteMergedCoco(root, options, splits[k], classes, sensors[k]);
  if (sensors.size() > 1) WriteMultiviewTargets(root, splits[0], sensors);
  return frames;
}

}  // namespace cadsynth
