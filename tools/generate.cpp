#include "tools/generate.h"

#include <atomic>
#include <chrono>
#include <memory>
#include <sstream>
#include <system_error>
#include <unistd.h>

#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include "cad/error.h"
#include "cad/assembly.h"
#include "cad/import.h"
#include "dataset/bop.h"
#include "render/renderer.h"
#include "variants/arrangement.h"
#include "variants/builtin.h"

namespace cadsynth {
namespace {

Assembly LoadSource(const PartSource& source, const RunSpec& spec) {
  if (source.kind == PartSource::Kind::kBuiltinDefault) return MakeDefaultParts(spec.tessellation);
  ImportOptions options;
  options.tessellation = spec.tessellation;
  options.crease_angle_rad = spec.crease_angle_rad;
  options.unit = source.unit;
  options.encoding = source.encoding;
  try {
    return ImportCad(source.path, options);
  } catch (const Error& e) {
    throw Error(source.where.empty() ? e.what() : source.where + ": " + e.what());
  }
}

// Removes a folder tree on scope exit unless released.
class StagingFolder {
 public:
  explicit StagingFolder(std::filesystem::path path) : path_(std::move(path)) {}
  ~StagingFolder() {
    if (!path_.empty()) {
      std::error_code ec;
      std::filesystem::remove_all(path_, ec);
    }
  }
  const std::filesystem::path& path() const { return path_; }
  void Release() { path_.clear(); }

 private:
  std::filesystem::path path_;
};

void MoveIntoPlace(const std::filesystem::path& staging, const std::filesystem::path& output,
                   bool overwrite) {
  std::error_code ec;
  if (std::filesystem::exists(output, ec)) {
    if (!overwrite) {
      throw Error(output.string() + ": already exists (pass --overwrite to replace it)");
    }
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

GenerateSummary Generate(const RunSpec& spec, const GenerateOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const auto info = [&](const std::string& line) {
    if (options.info) options.info(line);
  };
  if (options.output.empty()) throw Error("no output folder given");
  const std::filesystem::path output = std::filesystem::absolute(options.output).lexically_normal();
  std::error_code ec;
  if (std::filesystem::exists(output, ec) && !options.overwrite) {
    throw Error(output.string() + ": already exists (pass --overwrite to replace it)");
  }
  std::string why;
  if (!spec.intrinsics.Check(&why)) throw Error("camera: " + why);
  if (!spec.sweep.Check(&why)) throw Error("sweep: " + why);
  if (!spec.bop.Check(&why)) throw Error("output: " + why);
  if (spec.sources.empty()) throw Error("no parts to render");

  // Parts and instances of every source, in one assembly.
  Assembly all;
  std::vector<Part>& parts = all.parts;
  std::vector<Instance>& instances = all.instances;
  for (const PartSource& source : spec.sources) {
    Assembly assembly = LoadSource(source, spec);
    if (spec.class_by == RunSpec::ClassBy::kAssembly) assembly = FuseAssembly(assembly);
    std::ostringstream line;
    line << "read " << (source.kind == PartSource::Kind::kFile ? source.path.string() : "built-in parts")
         << " (" << assembly.format << "): '" << assembly.name << "', unit "
         << (assembly.length_unit.empty() ? "?" : assembly.length_unit)
         << ", " << assembly.parts.size() << " parts, " << assembly.instances.size() << " instances";
    info(line.str());
    const int offset = static_cast<int>(parts.size());
    for (Part& part : assembly.parts) parts.push_back(std::move(part));
    for (Instance instance : assembly.instances) {
      instance.part += offset;
      instances.push_back(std::move(instance));
    }
  }
  // The same shape from several files (or built in and imported) is one object.
  const size_t merged = MergeIdenticalParts(&all, 2.0 * spec.tessellation.linear_deflection_mm + 1e-3);
  if (merged > 0) info("merged " + std::to_string(merged) + " parts that repeat a shape of another file");

  std::vector<std::string> names, empty_groups;
  for (const Part& part : parts) names.push_back(part.name);
  const std::vector<ObjectClass> classes = AssignClasses(names, spec.class_groups, &empty_groups);
  for (const std::string& group : empty_groups) Warn("class '" + group + "' matches no part");
  for (size_t i = 0; i < parts.size(); ++i) {
    const Eigen::Vector3d size = parts[i].mesh.Bounds().sizes();
    std::ostringstream p;
    p.precision(4);
    p << "  obj_id " << i + 1 << ": '" << parts[i].name << "' " << size.x() << " x " << size.y()
      << " x " << size.z() << " mm, " << parts[i].mesh.num_triangles() << " triangles, class "
      << classes[i].id << " '" << classes[i].name << "'";
    info(p.str());
  }

  Scene scene = spec.look;
  scene.instances = Arrange(parts, instances, spec.arrangement);
  scene.part_colors.clear();
  for (size_t i = 0; i < parts.size(); ++i) {
    const Eigen::Vector3f palette = PaletteColor(static_cast<int>(i));
    scene.part_colors.push_back(spec.cad_colors ? parts[i].color.value_or(palette) : palette);
  }
  if (!spec.cad_colors) {
    for (Instance& instance : scene.instances) instance.color.reset();
  }
  const Renderer renderer(parts, scene, spec.render);

  std::vector<int> obj_ids;
  for (const Instance& instance : scene.instances) obj_ids.push_back(instance.part + 1);
  const std::vector<SweepView> views = ExpandSweep(spec.sweep);

  // Everything goes to a hidden staging folder beside the output, renamed into place at the end.
  std::filesystem::create_directories(output.parent_path(), ec);
  if (ec) throw Error(output.parent_path().string() + ": cannot create folder: " + ec.message());
  StagingFolder staging(output.parent_path() /
                        ("." + output.filename().string() + ".partial-" + std::to_string(::getpid())));
  std::filesystem::remove_all(staging.path(), ec);

  WriteBopCamera(staging.path(), spec.intrinsics, spec.bop);
  WriteBopModels(staging.path(), parts, classes);
  BopSceneWriter writer(staging.path(), /*scene_id=*/0, spec.bop, obj_ids);

  // cast -> encode + write, a bounded number of frames in flight.
  std::atomic<size_t> done{0};
  size_t next = 0;
  const size_t tokens = 2 * static_cast<size_t>(tbb::this_task_arena::max_concurrency());
  using FramePtr = std::shared_ptr<const Frame>;
  tbb::parallel_pipeline(
      tokens,
      tbb::make_filter<void, size_t>(tbb::filter_mode::serial_in_order,
                                     [&](tbb::flow_control& control) -> size_t {
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
                writer.WriteFrame(static_cast<int>(item.first), *item.second);
                const size_t n = ++done;
                if (options.progress) options.progress(n, views.size());
              }));
  writer.Finish();
  MoveIntoPlace(staging.path(), output, options.overwrite);
  staging.Release();

  GenerateSummary summary;
  summary.frames = views.size();
  summary.objects = parts.size();
  summary.instances = scene.instances.size();
  summary.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace cadsynth
