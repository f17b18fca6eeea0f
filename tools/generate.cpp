#include "tools/generate.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <system_error>

#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include "cad/assembly.h"
#include "cad/error.h"
#include "cad/import.h"
#include "dataset/bop.h"
#include "dataset/file_io.h"
#include "dataset/paper_layout.h"
#include "render/renderer.h"
#include "variants/arrangement.h"
#include "variants/families.h"

namespace cadsynth {
namespace {

using Json = nlohmann::ordered_json;

// One thing to build: a file, or one variant of a family; a rigid group in its scene.
struct Job {
  int scene = 0;
  const PartSource* source = nullptr;
  size_t variant = 0;
  std::string id;  // stable: scene/entry/family-or-file/variant
  Assembly assembly;
  std::string error;
};


Json ParamsJson(const ParamValues& values) {
  Json out = Json::object();
  for (const auto& [name, value] : values) {
    if (const double* x = std::get_if<double>(&value)) out[name] = *x; else out[name] = std::get<std::string>(value);
  }
  return out;
}

void Build(const RunSpec& spec, Job* job) {
  ImportOptions options;
  options.tessellation = spec.tessellation;
  options.crease_angle_rad = spec.crease_angle_rad;
  const PartSource& source = *job->source;
  try {
    if (source.kind == PartSource::Kind::kFile) {
      options.unit = source.unit;
      options.encoding = source.encoding;
      job->assembly = ImportCad(source.path, options);
    } else {
      job->assembly = BuildVariant(*FindFamily(source.family), source.variants[job->variant], options);
    }
    if (spec.class_by == RunSpec::ClassBy::kAssembly) job->assembly = FuseAssembly(job->assembly);
  } catch (const Error& e) {
    std::string where = source.where.empty() ? "" : source.where + ": ";
    if (source.kind == PartSource::Kind::kFamily) {
      where += "variant " + std::to_string(job->variant) + " (" + DescribeParams(source.variants[job->variant]) + "): ";
    }
    job->error = where + e.what();
  }
}

}  // namespace

std::vector<std::string> PlacementWarnings(const std::vector<Part>& parts, const std::vector<Instance>& instances,
                                           const Intrinsics& k, const SweepOptions& sweep) {
  std::vector<std::string> warnings;
  if (instances.empty() || sweep.radius_mm.empty()) return warnings;
  const double nearest = *std::min_element(sweep.radius_mm.begin(), sweep.radius_mm.end());
  const double farthest = *std::max_element(sweep.radius_mm.begin(), sweep.radius_mm.end());
  // The camera always looks at the target: the scene must fit in the cone of the narrower half
  // field of view at the nearest radius.
  const double half_fov = std::min(std::atan2(std::min(k.cx, k.width - k.cx), k.fx),
                                   std::atan2(std::min(k.cy, k.height - k.cy), k.fy));
  double reach = 0;
  for (const Instance& i : instances) {
    for (const Eigen::Vector3f& p : parts[i.part].mesh.positions) {
      reach = std::max(reach, (i.world_from_model * p.cast<double>() - sweep.target).norm());
    }
  }
  std::ostringstream out;
  out.precision(4);
  if (reach >= nearest) {
    out << "the scene reaches " << std::lround(reach) << " mm from the target, beyond the nearest camera radius "
        << std::lround(nearest) << " mm: the camera will be inside or touching it";
    warnings.push_back(out.str());
  } else if (std::asin(reach / nearest) > half_fov) {
    out << "the scene reaches " << std::lround(reach) << " mm from the target; at the nearest radius "
        << std::lround(nearest) << " mm the camera sees only " << std::lround(nearest * std::sin(half_fov))
        << " mm around it: objects will be cut off";
    warnings.push_back(out.str());
  }
  // The smallest object at the farthest radius.
  double smallest = 1e300;
  std::string name;
  for (const Instance& i : instances) {
    const double d = parts[i.part].mesh.Bounds().sizes().maxCoeff();
    if (d < smallest) smallest = d, name = parts[i.part].name;
  }
  const double pixels = k.fx * smallest / farthest;
  if (pixels < 10.0) {
    std::ostringstream small;
    small.precision(3);
    small << "'" << name << "' (" << smallest << " mm) spans only " << pixels << " px at the farthest radius "
          << std::lround(farthest) << " mm";
    warnings.push_back(small.str());
  }
  return warnings;
}

namespace {

// The size and CRC-32 of the running executable, read once ("unknown" where it cannot be read).
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

}  // namespace

std::string RunKey(const RunSpec& spec, const PreparedRun& prepared, const std::vector<SweepView>& views) {
  std::ostringstream key;
  key.precision(17);
  key << "cadsynth run key 2\n";
  if (!spec.recipe.empty()) key << "recipe\n" << ReadFileText(spec.recipe) << "\n";
  // The bytes of every CAD file, not only its name: a file edited between a kill and the rerun
  // (or between two shards) would otherwise mix frames of two geometries.
  std::set<std::filesystem::path> files;
  for (const SceneSpec& scene : spec.scenes) {
    for (const PartSource& source : scene.sources) {
      if (source.kind == PartSource::Kind::kFile) files.insert(source.path);
    }
  }
  for (const std::filesystem::path& file : files) {
    const std::string bytes = ReadFileText(file);
    key << "file " << file.string() << " " << bytes.size() << " " << Crc32(bytes) << "\n";
  }
  key << prepared.variants_json << "\n";
  const Intrinsics& k = spec.intrinsics;
  key << "camera " << k.width << " " << k.height << " " << k.fx << " " << k.fy << " " << k.cx << " " << k.cy << "\n";
  // Every described option (cad/schema.h), by name.
  const auto fields = [&key](const char* section, const auto& options) {
    key << section;
    std::decay_t<decltype(options)>::Fields(options, [&key](const auto& value, const Field& field) {
      key << " " << field.Name() << "=" << FieldText(value, field);
    });
    key << "\n";
  };
  fields("output", spec.bop);
  fields("render", spec.render);
  key << "min_visible_pixels " << spec.min_visible_pixels << "\n";
  for (const SweepView& v : views) key << v.world_from_cam.matrix().reshaped().transpose() << "\n";
  // Embree's kernels on this machine: different widths give different last bits.
  key << "trace " << TracingIsa(spec.render.isa) << "\n";
  // This build of cadsynth (our libraries are linked in statically): another build may write
  // other bytes, so it neither resumes this run nor joins its shards.
  key << "build " << BuildId() << "\n";
  return key.str();
}

namespace {

// One run at a time per output: an exclusive lock on STAGING.lock beside the staging folder.
class RunLock {
 public:
  explicit RunLock(const std::filesystem::path& staging) : path_(staging.string() + ".lock") {
    fd_ = ::open(path_.c_str(), O_CREAT | O_RDWR, 0644);
    if (fd_ < 0) throw Error(path_ + ": cannot create lock file: " + std::strerror(errno));
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd_);
      throw Error(staging.string() + ": another cadsynth run is writing this dataset");
    }
  }
  ~RunLock() { Release(); }
  void Release() {
    if (fd_ < 0) return;
    std::error_code ec;
    std::filesystem::remove(path_, ec);
    ::close(fd_);
    fd_ = -1;
  }

 private:
  std::string path_;
  int fd_ = -1;
};

void MoveIntoPlace(const std::filesystem::path& staging, const std::filesystem::path& output, bool overwrite) {
  std::error_code ec;
  if (std::filesystem::exists(output, ec)) {
    if (!overwrite) throw Error(output.string() + ": already exists (pass --overwrite to replace it)");
    std::filesystem::path old = output;
    old += ".old-" + std::to_string(::getpid());
    std::filesystem::rename(output, old, ec);
    if (ec) throw Error(output.string() + ": cannot move the old dataset aside: " + ec.message());
    std::filesystem::rename(staging, output, ec);
    if (ec) {
      std::error_code restore;
      std::filesystem::rename(old, output, restore);
      throw Error(output.string() + ": cannot move the new dataset into place: " + ec.message());
    }
    std::filesystem::remove_all(old, ec);
    return;
  }
  std::filesystem::rename(staging, output, ec);
  if (ec) throw Error(output.string() + ": cannot move the dataset into place: " + ec.message());
}

}  // namespace

PreparedRun Prepare(const RunSpec& spec, const std::function<void(const std::string&)>& info_sink) {
  const auto info = [&](const std::string& line) {
    if (info_sink) info_sink(line);
  };
  if (spec.scenes.empty()) throw Error("no scenes to render");
  // Every file and every variant, built in parallel; errors reported in recipe order.
  std::vector<Job> jobs;
  for (size_t s = 0; s < spec.scenes.size(); ++s) {
    const SceneSpec& scene = spec.scenes[s];
    if (scene.sources.empty()) throw Error("scene '" + scene.name + "' has no parts");
    for (size_t e = 0; e < scene.sources.size(); ++e) {
      const PartSource& source = scene.sources[e];
      const std::string base = scene.name + "/" + std::to_string(e) + "/";
      if (source.kind == PartSource::Kind::kFile) {
        jobs.push_back({static_cast<int>(s), &source, 0, base + source.path.filename().string(), {}, {}});
      } else {
        for (size_t v = 0; v < source.variants.size(); ++v) {
          jobs.push_back({static_cast<int>(s), &source, v, base + source.family + "/" + std::to_string(v), {}, {}});
        }
      }
    }
  }
  tbb::parallel_for(size_t{0}, jobs.size(), [&](size_t j) { Build(spec, &jobs[j]); });
  for (const Job& job : jobs) {
    if (!job.error.empty()) throw Error(job.error);
  }

  // One list of parts; instances remember their job (a rigid group) and scene.
  Assembly all;
  std::vector<int> job_of_instance;
  std::vector<std::string> label_of_part;
  for (size_t j = 0; j < jobs.size(); ++j) {
    Assembly& a = jobs[j].assembly;
    const PartSource& source = *jobs[j].source;
    if (source.kind == PartSource::Kind::kFile) {
      std::ostringstream line;
      line << "read " << source.path.string() << " (" << a.format << "): '" << a.name << "', unit "
           << (a.length_unit.empty() ? "?" : a.length_unit) << ", " << a.parts.size() << " parts, "
           << a.instances.size() << " instances";
      info(line.str());
    }
    const int offset = static_cast<int>(all.parts.size());
    for (Part& part : a.parts) {
      label_of_part.push_back(source.one_class ? source.family : std::string());
      all.parts.push_back(std::move(part));
    }
    for (Instance instance : a.instances) {
      instance.part += offset;
      all.instances.push_back(std::move(instance));
      job_of_instance.push_back(static_cast<int>(j));
    }
  }
  for (const SceneSpec& scene : spec.scenes) {
    for (const PartSource& source : scene.sources) {
      if (source.kind == PartSource::Kind::kFamily) {
        info("built " + std::to_string(source.variants.size()) + " variant(s) of " + source.family + " for scene '" +
             scene.name + "'");
      }
    }
  }
  // The same shape from several files, variants or scenes is one object.
  {
    std::vector<int> first_instance_part(all.instances.size());
    for (size_t i = 0; i < all.instances.size(); ++i) first_instance_part[i] = all.instances[i].part;
    const size_t merged = MergeIdenticalParts(&all, 2.0 * spec.tessellation.linear_deflection_mm + 1e-3);
    if (merged > 0) info("merged " + std::to_string(merged) + " parts that repeat the shape of another");
    std::vector<std::string> labels(all.parts.size());
    for (size_t i = 0; i < all.instances.size(); ++i) {
      std::string& label = labels[all.instances[i].part];
      if (label.empty()) label = label_of_part[first_instance_part[i]];
    }
    label_of_part = std::move(labels);
  }
  std::vector<Part>& parts = all.parts;
  std::vector<std::string> names, empty_groups;
  for (const Part& part : parts) names.push_back(part.name);
  const std::vector<ObjectClass> classes = AssignClasses(names, label_of_part, spec.class_groups, &empty_groups);
  for (const std::string& group : empty_groups) Warn("class '" + group + "' matches no part");
  for (size_t i = 0; i < parts.size(); ++i) {
    const Eigen::Vector3d size = parts[i].mesh.Bounds().sizes();
    std::ostringstream p;
    p.precision(4);
    p << "  obj_id " << i + 1 << ": '" << parts[i].name << "' " << size.x() << " x " << size.y() << " x "
      << size.z() << " mm, " << parts[i].mesh.num_triangles() << " triangles, class " << classes[i].id << " '"
      << classes[i].name << "'";
    info(p.str());
  }

  // Scenes: arrange each scene's groups on the floor.
  PreparedRun prepared;
  struct SceneRun {
    Scene scene;
    std::vector<int> obj_ids;
  };
  std::vector<SceneRun> runs(spec.scenes.size());
  for (size_t s = 0; s < spec.scenes.size(); ++s) {
    std::vector<Instance> instances;
    std::vector<int> groups;
    for (size_t i = 0; i < all.instances.size(); ++i) {
      if (jobs[job_of_instance[i]].scene != static_cast<int>(s)) continue;
      instances.push_back(all.instances[i]);
      groups.push_back(job_of_instance[i]);
    }
    SceneRun& run = runs[s];
    run.scene = spec.look;
    try {
      run.scene.instances = Arrange(parts, instances, spec.scenes[s].arrangement, groups).instances;
    } catch (const Error& e) {
      throw Error("scene '" + spec.scenes[s].name + "': " + e.what());
    }
    run.scene.part_colors.clear();
    for (size_t i = 0; i < parts.size(); ++i) {
      const Eigen::Vector3f palette = PaletteColor(static_cast<int>(i));
      run.scene.part_colors.push_back(spec.cad_colors ? parts[i].color.value_or(palette) : palette);
    }
    if (!spec.cad_colors) {
      for (Instance& instance : run.scene.instances) instance.color.reset();
    }
    for (const Instance& instance : run.scene.instances) run.obj_ids.push_back(instance.part + 1);
  }
  // variants.json: what each file or variant is, and which objects it became.
  Json variants = Json::array();
  for (size_t j = 0; j < jobs.size(); ++j) {
    std::set<int> obj_ids, class_ids;
    for (size_t i = 0; i < all.instances.size(); ++i) {
      if (job_of_instance[i] != static_cast<int>(j)) continue;
      obj_ids.insert(all.instances[i].part + 1);
      class_ids.insert(classes[all.instances[i].part].id);
    }
    const PartSource& source = *jobs[j].source;
    Json entry = {{"id", jobs[j].id}, {"scene_id", jobs[j].scene}, {"scene", spec.scenes[jobs[j].scene].name}};
    if (source.kind == PartSource::Kind::kFile) {
      entry["file"] = source.path.string();
    } else {
      entry["family"] = source.family;
      entry["params"] = ParamsJson(source.variants[jobs[j].variant]);
    }
    entry["obj_ids"] = obj_ids;
    entry["class_ids"] = class_ids;
    variants.push_back(entry);
  }
  prepared.variants_json = Json{{"variants", variants}}.dump(2) + "\n";

  for (SceneRun& run : runs) {
    prepared.scenes.push_back(std::move(run.scene));
    prepared.obj_ids.push_back(std::move(run.obj_ids));
  }
  prepared.parts = std::move(all.parts);
  prepared.classes = classes;
  return prepared;
}

GenerateSummary Generate(const RunSpec& spec, const GenerateOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (options.output.empty()) throw Error("no output folder given");
  const std::filesystem::path output = std::filesystem::absolute(options.output).lexically_normal();
  const std::optional<ShardSpec>& shard = options.shard;
  std::error_code ec;
  if (!shard && std::filesystem::exists(output, ec) && !options.overwrite) {
    throw Error(output.string() + ": already exists (pass --overwrite to replace it)");
  }
  if (shard && options.overwrite) throw Error("--overwrite does not apply to shards (they share one folder)");
  std::string why;
  if (!spec.intrinsics.Check(&why)) throw Error("camera: " + why);
  if (!spec.sweep.Check(&why)) throw Error("sweep: " + why);
  if (!spec.bop.Check(&why)) throw Error("output: " + why);

  PreparedRun prepared = Prepare(spec, options.info);
  const std::vector<Part>& parts = prepared.parts;
  std::string why_sampler;
  if (!spec.sampler.Check(&why_sampler)) throw Error("sweep: " + why_sampler);
  const std::vector<SweepView> views = SampleViews(spec.sampler, spec.sweep);
  const bool common = !shard || shard->index == 0;  // writes the files every dataset has once
  if (common) {
    for (size_t s = 0; s < prepared.scenes.size(); ++s) {
      for (const std::string& warning : PlacementWarnings(parts, prepared.scenes[s].instances, spec.intrinsics, spec.sweep)) {
        Warn("scene '" + spec.scenes[s].name + "': " + warning);
      }
    }
  }
  // Work unit g = scene * views + view; a shard renders the units it owns.
  const auto owns = [&](size_t scene, size_t view) { return !shard || shard->Owns(scene * views.size() + view); };
  size_t total_frames = 0;
  for (size_t s = 0; s < prepared.scenes.size(); ++s) {
    for (size_t i = 0; i < views.size(); ++i) total_frames += owns(s, i);
  }

  const auto info = [&](const std::string& line) {
    if (options.info) options.info(line);
  };
  const std::string run_key = RunKey(spec, prepared, views);
  info("tracing with Embree's " + TracingIsa(spec.render.isa) + " kernels");
  // A single run writes to a hidden staging folder beside the output, renamed into place at the
  // end. An interrupted run (killed, disk full) leaves it; the same run started again continues
  // from the frames it completed, if its run key (recipe text, parts, views, output options)
  // matches. Shards write into the output folder itself and agree on the key there.
  std::filesystem::path root;
  std::unique_ptr<RunLock> lock;
  std::unique_ptr<ShardTree> tree;
  if (shard) {
    root = output;
    tree = std::make_unique<ShardTree>(output, *shard, run_key);
  } else {
    std::filesystem::create_directories(output.parent_path(), ec);
    if (ec) throw Error(output.parent_path().string() + ": cannot create folder: " + ec.message());
    root = output.parent_path() / ("." + output.filename().string() + ".partial");
    lock = std::make_unique<RunLock>(root);
    const std::filesystem::path key_path = root / ".run_key";
    std::ifstream in(key_path);
    std::stringstream old_key;
    old_key << in.rdbuf();
    if (old_key.str() != run_key) {
      if (std::filesystem::exists(root, ec)) info("starting over: " + root.string() + " holds an interrupted run of something else");
      std::filesystem::remove_all(root, ec);
      CreateFolder(root);
      WriteFileAtomic(key_path, run_key);
    } else {
      info("resuming the interrupted run in " + root.string());
    }
  }
  // The staging folder (or shard tree) is kept on errors from here on: a rerun resumes from it.
  std::atomic<size_t> done{0}, empty_views{0}, sparse_views{0};
  size_t resumed = 0, damaged = 0, frames = 0;
  std::vector<SceneSplit> splits;
  std::vector<std::unique_ptr<BopSceneWriter>> writers;
  try {
    if (common) {
      WriteBopCamera(root, spec.intrinsics, spec.bop);
      WriteBopModels(root, parts, prepared.classes);
      WriteModelPoints(root, parts, spec.bop);
      WriteFileAtomic(root / "variants.json", prepared.variants_json);
    }
    std::vector<BopSceneWriter::CocoCategory> categories;
    for (size_t p = 0; p < parts.size(); ++p) {
      categories.push_back({static_cast<int>(p) + 1, parts[p].name, prepared.classes[p].name});
    }
    if (shard && shard->index == 0) {
      ShardRunInfo run;
      run.shards = shard->count;
      run.views = views.size();
      run.bop = spec.bop;
      run.obj_ids = prepared.obj_ids;
      run.categories = categories;
      run.classes = prepared.classes;
      tree->WriteRunInfo(run);
    }

    // Every scene's writers first: frames of an interrupted attempt count when every file still
    // matches their manifest entry; the others are rendered (again).
    std::vector<std::unique_ptr<PaperSceneWriter>> papers;
    for (size_t s = 0; s < prepared.scenes.size(); ++s) {
      auto& writer = *writers.emplace_back(
          std::make_unique<BopSceneWriter>(root, static_cast<int>(s), spec.bop, prepared.obj_ids[s]));
      if (common) writer.WriteWorldPoses(prepared.scenes[s].instances);
      writer.SetCocoCategories(categories);
      std::vector<PaperInstance> paper_instances;
      for (size_t i = 0; i < prepared.scenes[s].instances.size(); ++i) {
        const Instance& instance = prepared.scenes[s].instances[i];
        paper_instances.push_back({prepared.obj_ids[s][i], prepared.classes[static_cast<size_t>(instance.part)],
                                   instance.name, instance.world_from_model});
      }
      papers.push_back(
          std::make_unique<PaperSceneWriter>(root, static_cast<int>(s), spec.bop, std::move(paper_instances)));
      std::vector<int> earlier;
      for (int id : writer.WrittenFrames()) {
        if (id >= 0 && static_cast<size_t>(id) < views.size() && owns(s, static_cast<size_t>(id))) earlier.push_back(id);
      }
      std::vector<std::string> problems(earlier.size());
      tbb::parallel_for(size_t{0}, earlier.size(), [&](size_t k) { problems[k] = writer.CheckFrame(earlier[k]); });
      for (size_t k = 0; k < earlier.size(); ++k) {
        if (problems[k].empty()) {
          ++resumed;
          continue;
        }
        Warn(problems[k] + ": rendering image " + std::to_string(earlier[k]) + " again");
        writer.ForgetFrame(earlier[k]);
        ++damaged;
      }
    }
    // Progress counts the frames this attempt renders.
    const size_t to_render = total_frames - resumed;
    if (options.progress) options.progress(0, to_render);

    // Render scene by scene: cast -> encode + write, a bounded number of frames in flight. Views
    // showing too little of the scene are skipped (image ids keep their view index).
    for (size_t s = 0; s < prepared.scenes.size(); ++s) {
      RenderOptions render = spec.render;
      render.amodal_depth = spec.bop.visibility == BopOptions::Visibility::kBop19;
      const Renderer renderer(parts, prepared.scenes[s], render);
      BopSceneWriter& writer = *writers[s];
      const PaperSceneWriter& paper = *papers[s];
      size_t next = 0;
      const size_t tokens = 2 * static_cast<size_t>(tbb::this_task_arena::max_concurrency());
      using FramePtr = std::shared_ptr<const Frame>;
      tbb::parallel_pipeline(
          tokens,
          tbb::make_filter<void, size_t>(tbb::filter_mode::serial_in_order,
                                         [&](tbb::flow_control& control) -> size_t {
                                           while (next < views.size() && (!owns(s, next) || writer.HasFrame(static_cast<int>(next)))) {
                                             ++next;
                                           }
                                           if (next >= views.size()) {
                                             control.stop();
                                             return 0;
                                           }
                                           return next++;
                                         }) &
              tbb::make_filter<size_t, std::pair<size_t, FramePtr>>(
                  tbb::filter_mode::parallel,
                  [&](size_t i) {
                    const Camera camera{spec.intrinsics, views[i].world_from_cam};
                    return std::make_pair(i, std::make_shared<const Frame>(renderer.Render(camera)));
                  }) &
              tbb::make_filter<std::pair<size_t, FramePtr>, void>(
                  tbb::filter_mode::parallel, [&](const std::pair<size_t, FramePtr>& item) {
                    int visible = 0;
                    for (const Frame::InstanceTruth& t : item.second->instances) visible += t.px_count_visib;
                    if (spec.min_visible_pixels > 0 && visible < spec.min_visible_pixels) {
                      ++(visible == 0 ? empty_views : sparse_views);
                    } else {
                      writer.WriteFrame(static_cast<int>(item.first), *item.second, [&](FileLog& files) {
                        paper.WriteFrame(static_cast<int>(item.first), *item.second, writer.scene_dir(), &files);
                      });
                    }
                    const size_t n = ++done;
                    if (options.progress) options.progress(n, to_render);
                  }));
      for (int id : writer.WrittenFrames()) frames += owns(s, static_cast<size_t>(id));
      if (!shard) splits.push_back(writer.Finish());
    }
  } catch (const Error& e) {
    throw Error(std::string(e.what()) + "\n(the complete frames are kept in " + root.string() +
                ": the same command continues from them)");
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (shard) {
    std::ostringstream marker;
    marker << "{\"shard\": " << shard->index << ", \"of\": " << shard->count << ", \"units\": " << total_frames
           << ", \"frames\": " << frames << ", \"skipped_empty\": " << empty_views
           << ", \"skipped_sparse\": " << sparse_views << ", \"seconds\": " << seconds << "}";
    tree->MarkDone(marker.str());
  } else {
    WriteSplits(root, splits);
    WriteMergedCoco(root, spec.bop, splits, prepared.classes);
    for (const auto& writer : writers) writer->RemoveFragments();
    std::filesystem::remove(root / ".run_key", ec);
    lock->Release();
    MoveIntoPlace(root, output, options.overwrite);
  }
  if (resumed > 0) info("resumed: " + std::to_string(resumed) + " frames were already written");
  if (damaged > 0) info("rendered again: " + std::to_string(damaged) + " frames whose files did not match the manifest");

  GenerateSummary summary;
  summary.skipped_empty = empty_views;
  summary.skipped_sparse = sparse_views;
  summary.frames = frames;
  summary.resumed = resumed;
  summary.scenes = prepared.scenes.size();
  summary.objects = parts.size();
  summary.instances = 0;
  for (const Scene& scene : prepared.scenes) summary.instances += scene.instances.size();
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace cadsynth
