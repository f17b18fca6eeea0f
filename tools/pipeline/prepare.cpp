#include "tools/pipeline/prepare.h"

#include <fnmatch.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <exception>
#include <map>
#include <mutex>
#include <set>
#include <sstream>

#include <tbb/parallel_for.h>
#include <nlohmann/json.hpp>

#include "cad/assembly.h"
#include "cad/core/error.h"
#include "cad/core/schema.h"
#include "cad/hull.h"
#include "cad/import.h"
#include "cad/part_cache.h"
#include "cad/shape.h"
#include "cad/symmetry.h"
#include "dataset/file_io.h"
#include "render/randomize.h"
#include "variants/arrangement.h"
#include "variants/families.h"

namespace cadsynth {
namespace {

using Json = nlohmann::ordered_json;

// A length for a message: whole millimetres (lround overflows past 9e18: printed as a huge
// negative number), or three significant digits when it is that large.
std::string Mm(double x) {
  if (std::abs(x) < 1e12) return std::to_string(std::llround(x));
  std::ostringstream out;
  out.precision(3);
  out << x;
  return out.str();
}

// Inputs large enough to announce before working on them.
constexpr uintmax_t kLargeFileBytes = 50u << 20;
constexpr size_t kLargeMeshVertices = 1000000;

// One thing to build: a file, or one variant of a family; a rigid group in its scene.
struct Job {
  int scene = 0;
  const PartSource* source = nullptr;
  size_t variant = 0;
  std::string id;  // stable: scene/entry/family-or-file/variant
  Assembly assembly;
  std::vector<std::string> warnings;  // reading or building it gave (also from the cache)
  std::string error;
};

Json ParamsJson(const ParamValues& values) {
  Json out = Json::object();
  for (const auto& [name, value] : values) {
    if (const double* x = std::get_if<double>(&value))
      out[name] = *x;
    else
      out[name] = std::get<std::string>(value);
  }
  return out;
}

// The options an import or variant depends on, into a cache key.
void HashOptions(KeyHasher* hasher, const ImportOptions& options) {
  TessellationOptions::Fields(options.tessellation, [&](const auto& value, const Field& field) {
    hasher->Text(field.Name()).Text(FieldText(value, field));
  });
  hasher->Text(options.unit).Text(options.encoding).Value(options.crease_angle_rad);
}

// Formats whose file holds all of the part (OBJ, glTF and COLLADA may read other files: their
// material or buffer files, which the key would miss).
bool SelfContained(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* e : {".step", ".stp", ".p21", ".iges", ".igs", ".brep", ".rle", ".stl", ".ply",
                        ".off", ".glb", ".3mf"}) {
    if (ext == e) return true;
  }
  return false;
}

// The key of a job's assembly, or nothing when it cannot be cached.
std::optional<CacheKey> ImportKey(const PartCache& cache, const ImportOptions& options,
                                  const PartSource& source, size_t variant) {
  KeyHasher hasher;
  cache.Start(&hasher, "import 2");  // 2: meshes keep their texture coordinates
  HashOptions(&hasher, options);
  const auto hash_file = [&](const std::filesystem::path& path) {
    hasher.Text(path.string()).Text(ReadFileText(path));  // the path: warnings name it
  };
  if (source.kind == PartSource::Kind::kFile) {
    if (!SelfContained(source.path)) return std::nullopt;
    hash_file(source.path);
  } else {
    hasher.Text(source.family);
    for (const auto& [name, value] : source.variants[variant]) {
      hasher.Text(name);
      if (const double* x = std::get_if<double>(&value)) {
        hasher.Value(*x);
      } else {
        const std::string& text = std::get<std::string>(value);
        hasher.Text(text);
        if (name == "file") {  // a family made from a file (scaled): its content
          if (!SelfContained(text)) return std::nullopt;
          hash_file(text);
        }
      }
    }
  }
  return hasher.Key();
}

void Build(const RunSpec& spec, const PartCache* cache, const ReaderProcess* reader, Job* job) {
  ImportOptions options;
  options.tessellation = spec.tessellation;
  options.crease_angle_rad = spec.crease_angle_rad;
  const PartSource& source = *job->source;
  if (source.kind == PartSource::Kind::kFile) {
    options.unit = source.unit;
    options.encoding = source.encoding;
  }
  // Warnings are kept with the job (and its cache entry) and reported in recipe order.
  WarningCapture capture;
  try {
    std::optional<CacheKey> key;
    if (cache) {
      try {
        key = ImportKey(*cache, options, source, job->variant);
      } catch (const Error&) {  // an unreadable file: the importer says why
      }
    }
    bool cached = false;
    if (key) {
      if (const std::optional<std::string> bytes = cache->Load("import", *key)) {
        try {
          job->assembly = DecodeAssembly(*bytes, &job->warnings);
          cached = true;
        } catch (const Error&) {  // damaged: built again below
        }
      }
    }
    if (!cached) {
      if (source.kind == PartSource::Kind::kFile) {
        job->assembly = ImportGuarded(source.path, options, reader, &job->warnings);
      } else {
        job->assembly =
            BuildVariant(*FindFamily(source.family), source.variants[job->variant], options);
      }
      std::vector<std::string> more = capture.Take();
      job->warnings.insert(job->warnings.end(), more.begin(), more.end());
      if (key) cache->Store("import", *key, EncodeAssembly(job->assembly, job->warnings));
    }
    // The designer's up axis turned to +z (recipe `up:`), before fusing and arranging.
    if (!source.z_from_up.isIdentity()) {
      const Eigen::Isometry3d turn(source.z_from_up);
      for (Instance& instance : job->assembly.instances)
        instance.world_from_model = turn * instance.world_from_model;
    }
    if (spec.class_by == RunSpec::ClassBy::kAssembly) job->assembly = FuseAssembly(job->assembly);
  } catch (const Error& e) {
    std::string where = source.where.empty() ? "" : source.where + ": ";
    if (source.kind == PartSource::Kind::kFamily) {
      where += "variant " + std::to_string(job->variant) + " (" +
               DescribeParams(source.variants[job->variant], FindFamily(source.family)) + "): ";
    }
    job->error = where + e.what();
  }
  std::vector<std::string> rest = capture.Take();
  job->warnings.insert(job->warnings.end(), rest.begin(), rest.end());
}

// The convex hull of a part's mesh, read from the cache or computed (and stored); null for a
// flat part.
std::shared_ptr<const ConvexHull> PartHull(const Mesh& mesh, const PartCache* cache) {
  std::optional<CacheKey> key;
  if (cache) {
    KeyHasher hasher;
    cache->Start(&hasher, "hull 2");
    hasher.Geometry(mesh);
    key = hasher.Key();
    if (const std::optional<std::string> bytes = cache->Load("hull", *key)) {
      try {
        ConvexHull hull = DecodeHull(*bytes);
        if (hull.empty()) return nullptr;
        return std::make_shared<const ConvexHull>(std::move(hull));
      } catch (const Error&) {  // damaged: computed again below
      }
    }
  }
  std::shared_ptr<const ConvexHull> hull;
  try {
    hull = std::make_shared<const ConvexHull>(ComputeConvexHull(mesh));
  } catch (const Error&) {  // flat: no hull (stored as an empty one)
  }
  if (key) cache->Store("hull", *key, EncodeHull(hull ? *hull : ConvexHull()));
  return hull;
}

// A part's collision shape for piles, read from the cache or computed (and stored): a concave
// part's decomposition takes up to a second, once per part for a whole farm.
CollisionShape PartCollisionShape(const Part& part, const PartCache* cache) {
  const CollisionOptions options;
  std::optional<CacheKey> key;
  if (cache) {
    KeyHasher hasher;
    cache->Start(&hasher, "collision 3");
    hasher.Geometry(part.mesh)
        .Value(part.watertight)
        .Value(part.mass.volume_mm3)
        .Value(options.convex_fraction)
        .Value(options.concavity)
        .Value(options.max_pieces)
        .Value(options.max_triangles)
        .Value(options.max_corners)
        .Value(options.tolerance_mm);
    key = hasher.Key();
    if (const std::optional<std::string> bytes = cache->Load("collision", *key)) {
      try {
        return DecodeCollisionShape(*bytes);
      } catch (const Error&) {  // damaged: computed again below
      }
    }
  }
  CollisionShape shape = MakeCollisionShape(part, options);
  if (key) cache->Store("collision", *key, EncodeCollisionShape(shape));
  return shape;
}

// Whether a rule's name, family and file patterns (shell globs, case-insensitive; empty matches
// anything) all match a part of `source` called `name`. File patterns without a '/' match the
// file's name wherever it lies.
template <typename Rule>
bool RuleMatches(const Rule& rule, const std::string& name, const PartSource& source) {
  const bool from_file = source.kind == PartSource::Kind::kFile;
  const std::string family = from_file ? "" : source.family;
  const std::string file = from_file ? source.path.string() : "";
  const auto matches = [](const std::string& pattern, const std::string& text) {
    if (pattern.empty()) return true;
    if (text.empty()) return false;
    const std::string subject = pattern.find('/') == std::string::npos
                                    ? std::filesystem::path(text).filename().string()
                                    : text;
    return fnmatch(pattern.c_str(), subject.c_str(), FNM_CASEFOLD) == 0;
  };
  return matches(rule.name, name) && matches(rule.family, family) && matches(rule.file, file);
}

}  // namespace

std::vector<std::string> PlacementWarnings(const std::vector<Part>& parts,
                                           const std::vector<Instance>& instances,
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
    out << "the scene reaches " << Mm(reach)
        << " mm from the target, beyond the nearest camera radius " << Mm(nearest)
        << " mm: the camera will be inside or touching it";
    warnings.push_back(out.str());
  } else if (std::asin(reach / nearest) > half_fov) {
    out << "the scene reaches " << Mm(reach) << " mm from the target; at the nearest radius "
        << Mm(nearest) << " mm the camera sees only " << Mm(nearest * std::sin(half_fov))
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
    small << "'" << name << "' (" << smallest << " mm) spans only " << pixels
          << " px at the farthest radius " << Mm(farthest) << " mm";
    warnings.push_back(small.str());
  }
  return warnings;
}

PreparedRun Prepare(const RunSpec& spec, const std::function<void(const std::string&)>& info_sink,
                    const PartCache* cache, const ReaderProcess* reader) {
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
        jobs.push_back(
            {static_cast<int>(s), &source, 0, base + source.path.filename().string(), {}, {}, {}});
      } else {
        for (size_t v = 0; v < source.variants.size(); ++v) {
          jobs.push_back({static_cast<int>(s),
                          &source,
                          v,
                          base + source.family + "/" + std::to_string(v),
                          {},
                          {},
                          {}});
        }
      }
    }
  }
  // Large files take seconds: say so before the wait (the lines after it report what was read).
  for (const Job& job : jobs) {
    if (job.source->kind != PartSource::Kind::kFile) continue;
    std::error_code ec;
    const auto bytes = std::filesystem::file_size(job.source->path, ec);
    if (!ec && bytes >= kLargeFileBytes) {
      info("reading " + job.source->path.string() + " (" + std::to_string(bytes >> 20) + " MB)");
    }
  }
  // Many sources (a family grid): a line at every tenth built.
  std::atomic<size_t> built{0};
  std::mutex info_mutex;
  tbb::parallel_for(size_t{0}, jobs.size(), [&](size_t j) {
    Build(spec, cache, reader, &jobs[j]);
    const size_t n = ++built, total = jobs.size();
    if (total >= 20 && (n * 10 / total) != ((n - 1) * 10 / total)) {
      std::lock_guard<std::mutex> lock(info_mutex);
      info("built " + std::to_string(n) + " of " + std::to_string(total) + " parts and variants");
    }
  });
  for (const Job& job : jobs) {
    for (const std::string& warning : job.warnings) Warn(warning);
    if (!job.error.empty()) throw Error(job.error);
  }
  // Containers from files (container type: file): read like part files (and cached alike), all
  // their instances one mesh, centred over the origin and standing on the floor.
  std::vector<Mesh> container_mesh(spec.scenes.size());
  {
    std::vector<Job> containers;
    for (size_t s = 0; s < spec.scenes.size(); ++s) {
      if (const auto& file = spec.scenes[s].container_file) {
        containers.push_back({static_cast<int>(s), &*file, 0, file->path.string(), {}, {}, {}});
      }
    }
    tbb::parallel_for(size_t{0}, containers.size(),
                      [&](size_t j) { Build(spec, cache, reader, &containers[j]); });
    for (Job& job : containers) {
      for (const std::string& warning : job.warnings) Warn(warning);
      if (!job.error.empty()) throw Error(job.error);
      Mesh& mesh = container_mesh[job.scene];
      for (const Instance& instance : job.assembly.instances) {
        Mesh placed = job.assembly.parts[instance.part].mesh;
        placed.Transform(instance.world_from_model);
        mesh.Append(placed);
      }
      if (mesh.empty()) {
        throw Error(job.source->where + ": " + job.source->path.string() +
                    ": the container file has no surfaces");
      }
      const Eigen::AlignedBox3d box = mesh.Bounds();
      mesh.Transform(Eigen::Isometry3d(
          Eigen::Translation3d(-box.center().x(), -box.center().y(), -box.min().z())));
      std::ostringstream line;
      line << "read container " << job.source->path.string() << ": " << mesh.triangles.size()
           << " triangles, " << box.sizes().x() << " x " << box.sizes().y() << " x "
           << box.sizes().z() << " mm";
      info(line.str());
    }
  }

  // Distractor objects (randomize.distractors.objects) of the recipe and of scenes with their
  // own: primitives by name, and every distinct part of each file or family variant (read like
  // part files, and cached alike). An object listed once but inherited by several scenes
  // (the same recipe place) is read once.
  struct DistractorCandidate {
    std::string name;
    DistractorObject::Kind kind = DistractorObject::Kind::kBox;
    Part part;  // kSource
  };
  std::vector<std::vector<DistractorCandidate>> distractor_candidates(spec.scenes.size());
  {
    std::vector<Job> sources;
    std::map<std::string, std::vector<size_t>> jobs_of;  // by where and what: its jobs
    // Everything that decides what a source builds: its place in the recipe, file, unit,
    // family and every variant's parameters.
    const auto what = [](const DistractorObject& o) {
      std::ostringstream key;
      key << o.where << "|" << o.source.path.string() << "|" << o.source.unit << "|"
          << o.source.encoding << "|" << o.source.family;
      for (const ParamValues& v : o.source.variants) key << "|" << ParamsJson(v).dump();
      return key.str();
    };
    for (size_t s = 0; s < spec.scenes.size(); ++s) {
      const RandomizeSpec& r =
          spec.scenes[s].randomize ? *spec.scenes[s].randomize : spec.randomize;
      if (!r.draws.distractors) continue;
      for (const DistractorObject& object : r.distractor_objects) {
        if (object.kind != DistractorObject::Kind::kSource || jobs_of.count(what(object))) continue;
        std::vector<size_t>& mine = jobs_of[what(object)];
        const PartSource& source = object.source;
        const size_t variants = source.kind == PartSource::Kind::kFile ? 1 : source.variants.size();
        for (size_t v = 0; v < variants; ++v) {
          mine.push_back(sources.size());
          sources.push_back({static_cast<int>(s),
                             &source,
                             v,
                             source.kind == PartSource::Kind::kFile
                                 ? source.path.string()
                                 : source.family + "/" + std::to_string(v),
                             {},
                             {},
                             {}});
        }
      }
    }
    tbb::parallel_for(size_t{0}, sources.size(),
                      [&](size_t j) { Build(spec, cache, reader, &sources[j]); });
    for (const Job& job : sources) {
      for (const std::string& warning : job.warnings) Warn(warning);
      if (!job.error.empty()) throw Error(job.error);
    }
    for (size_t s = 0; s < spec.scenes.size(); ++s) {
      const RandomizeSpec& r =
          spec.scenes[s].randomize ? *spec.scenes[s].randomize : spec.randomize;
      if (!r.draws.distractors) continue;
      for (const DistractorObject& object : r.distractor_objects) {
        if (object.kind != DistractorObject::Kind::kSource) {
          DistractorCandidate c;
          c.kind = object.kind;
          c.name = object.kind == DistractorObject::Kind::kBox        ? "box"
                   : object.kind == DistractorObject::Kind::kCylinder ? "cylinder"
                                                                      : "sphere";
          distractor_candidates[s].push_back(std::move(c));
          continue;
        }
        for (size_t j : jobs_of[what(object)]) {
          const Job& job = sources[j];
          const Assembly& a = job.assembly;
          for (const Part& part : a.parts) {
            DistractorCandidate c;
            c.kind = DistractorObject::Kind::kSource;
            c.name = job.id + (a.parts.size() > 1 ? "/" + part.name : std::string());
            c.part = part;
            distractor_candidates[s].push_back(std::move(c));
          }
        }
      }
      if (distractor_candidates[s].empty()) {
        throw Error("scene '" + spec.scenes[s].name +
                    "': randomize.distractors: its objects have no parts");
      }
    }
  }

  // One list of parts; instances remember their job (a rigid group) and scene.
  Assembly all;
  struct Detect {
    size_t part;
    double tolerance_mm;
    const PartSource* given = nullptr;  // a recipe's explicit list, measured instead
  };
  std::vector<Detect> detect;  // parts without declared symmetries, to look for them
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
      if (!source.given_symmetries.empty()) {
        if (a.parts.size() != 1) {
          throw Error(source.given_symmetries[0].where +
                      ": symmetry: a list is for a file of one " + "part; " + source.path.string() +
                      " has " + std::to_string(a.parts.size()));
        }
        detect.push_back({all.parts.size() - 1, source.symmetry_tolerance_mm, &source});
      } else if (source.detect_symmetry && all.parts.back().symmetries.empty()) {
        detect.push_back({all.parts.size() - 1, source.symmetry_tolerance_mm});
      }
    }
    for (Instance instance : a.instances) {
      instance.part += offset;
      all.instances.push_back(std::move(instance));
      job_of_instance.push_back(static_cast<int>(j));
    }
  }
  // Symmetries of the parts that declare none (imported files), found on their meshes, or as
  // the recipe lists them, measured on the meshes.
  {
    std::vector<DetectedSymmetries> found(detect.size());
    // Per listed entry, its own worst deviation (to name the entry that does not hold).
    std::vector<std::vector<double>> entry_deviation(detect.size());
    std::vector<std::string> failure(detect.size());  // why nothing could be measured
    tbb::parallel_for(size_t{0}, detect.size(), [&](size_t k) {
      const Part& part = all.parts[detect[k].part];
      if (part.mesh.triangles.empty()) {
        failure[k] = "its mesh has no triangles";
        return;
      }
      try {
        const SymmetryOptions options = PartSymmetryOptions(part, detect[k].tolerance_mm);
        if (detect[k].given == nullptr) {
          found[k] = DetectSymmetries(part.mesh, options);
          CompareBrepFaces(part, &found[k]);
          return;
        }
        // The list is in the part's CAD frame; an axis without a point passes through the
        // surface's centroid.
        const Eigen::Vector3d centre = MeasureSymmetries(part.mesh, {}, options).centre;
        const Eigen::Isometry3d model_from_cad = part.cad_from_model.inverse();
        Symmetries all_given;
        for (const PartSource::GivenSymmetry& g : detect[k].given->given_symmetries) {
          Symmetries one;
          const Eigen::Vector3d axis = model_from_cad.linear() * g.axis;
          const Eigen::Vector3d point = g.through ? model_from_cad * *g.through : centre;
          if (g.order == 0) {
            one.continuous.push_back({axis, point});
          } else {
            one.discrete.push_back(Eigen::Translation3d(point) *
                                   Eigen::AngleAxisd(2 * M_PI / g.order, axis) *
                                   Eigen::Translation3d(-point));
          }
          const DetectedSymmetries measured = MeasureSymmetries(part.mesh, one, options);
          double worst = 0;
          for (double d : measured.discrete_deviation_mm) worst = std::max(worst, d);
          for (double d : measured.continuous_deviation_mm) worst = std::max(worst, d);
          entry_deviation[k].push_back(worst);
          all_given.discrete.insert(all_given.discrete.end(), one.discrete.begin(),
                                    one.discrete.end());
          all_given.continuous.insert(all_given.continuous.end(), one.continuous.begin(),
                                      one.continuous.end());
        }
        found[k] = MeasureSymmetries(part.mesh, all_given, options);
        CompareBrepFaces(part, &found[k]);
      } catch (const Error& e) {
        failure[k] = e.what();  // reported below, in order
      }
    });
    for (size_t k = 0; k < detect.size(); ++k) {
      Part& part = all.parts[detect[k].part];
      if (!failure[k].empty()) {
        // A list the recipe gives must hold: it cannot be checked, so the run stops there.
        if (detect[k].given != nullptr) {
          throw Error(detect[k].given->given_symmetries[0].where +
                      ": symmetry: the list cannot be measured on '" + part.name +
                      "': " + failure[k]);
        }
        if (!part.mesh.triangles.empty())
          Warn("'" + part.name + "': no symmetries looked for (" + failure[k] + ")");
        continue;
      }
      if (detect[k].given != nullptr) {
        // Every listed symmetry, and every product of them, must hold within the tolerance.
        const auto& list = detect[k].given->given_symmetries;
        const auto mm = [](double v) {
          std::ostringstream text;
          text.precision(3);
          text << v << " mm";
          return text.str();
        };
        for (size_t e = 0; e < list.size(); ++e) {
          if (entry_deviation[k][e] > found[k].tolerance_mm) {
            throw Error(list[e].where + ": symmetry: this turn moves the surface of '" + part.name +
                        "' up to " + mm(entry_deviation[k][e]) + " off itself, beyond the " +
                        "tolerance of " + mm(found[k].tolerance_mm) +
                        " (raise symmetry_tolerance to accept it)");
          }
        }
        double worst = 0;
        for (double d : found[k].discrete_deviation_mm) worst = std::max(worst, d);
        if (worst > found[k].tolerance_mm) {
          throw Error(list[0].where +
                      ": symmetry: the listed turns combined move the surface of '" + part.name +
                      "' up to " + mm(worst) + " off itself, beyond the tolerance of " +
                      mm(found[k].tolerance_mm) + " (are the axes through the same point?)");
        }
      }
      part.symmetries = found[k].symmetries;
      if (part.symmetries.empty()) continue;
      info("symmetries of '" + part.name + "'" + (detect[k].given ? " (as listed)" : "") + ": " +
           DescribeSymmetries(found[k]));
    }
  }
  for (const SceneSpec& scene : spec.scenes) {
    for (const PartSource& source : scene.sources) {
      if (source.kind == PartSource::Kind::kFamily) {
        info("built " + std::to_string(source.variants.size()) + " variant(s) of " + source.family +
             " for scene '" + scene.name + "'");
      }
    }
  }
  // The same shape from several files, variants or scenes is one object.
  {
    std::vector<int> first_instance_part(all.instances.size());
    for (size_t i = 0; i < all.instances.size(); ++i)
      first_instance_part[i] = all.instances[i].part;
    const size_t merged =
        MergeIdenticalParts(&all, 2.0 * spec.tessellation.linear_deflection_mm + 1e-3, cache);
    if (merged > 0)
      info("merged " + std::to_string(merged) + " parts that repeat the shape of another");
    std::vector<std::string> labels(all.parts.size());
    for (size_t i = 0; i < all.instances.size(); ++i) {
      std::string& label = labels[all.instances[i].part];
      if (label.empty()) label = label_of_part[first_instance_part[i]];
    }
    label_of_part = std::move(labels);
  }
  std::vector<Part>& parts = all.parts;
  // Two objects of one name (some exporters call every body "SOLID") would be two COCO
  // categories and two classes of one name: the later ones get "_2", "_3", ...
  {
    std::set<std::string> used;
    for (const Part& part : parts) used.insert(part.name);
    std::set<std::string> taken;
    for (Part& part : parts) {
      if (taken.insert(part.name).second) continue;
      for (int k = 2;; ++k) {
        const std::string name = part.name + "_" + std::to_string(k);
        if (used.count(name) == 0 && taken.insert(name).second) {
          part.name = name;
          break;
        }
      }
    }
  }
  // Each part's convex hull once, for its stable poses and its diameter (flat parts have none).
  for (const Part& part : parts) {
    if (part.mesh.num_vertices() >= kLargeMeshVertices) {
      info("convex hull and diameter of '" + part.name + "' (" +
           std::to_string(part.mesh.num_vertices()) + " vertices)");
    }
  }
  tbb::parallel_for(size_t{0}, parts.size(),
                    [&](size_t i) { parts[i].hull = PartHull(parts[i].mesh, cache); });
  std::vector<std::string> names, empty_groups;
  for (const Part& part : parts) names.push_back(part.name);
  const std::vector<ObjectClass> classes =
      AssignClasses(names, label_of_part, spec.class_groups, &empty_groups);
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

  // Scenes: arrange each scene's groups on the floor.
  PreparedRun prepared;
  struct SceneRun {
    Scene scene;
    std::vector<int> obj_ids;
    Randomization randomization;
  };
  std::vector<SceneRun> runs(spec.scenes.size());
  std::vector<bool> used_rules(spec.material_rules.size(), false);
  std::vector<bool> used_randomize_rules(spec.randomize.part_rules.size(), false);
  bool recipe_randomize_used = false;
  // The collision shapes of the parts that piles and drops use, each made once (two piles of one
  // part would otherwise both decompose it on a cold cache); a shape's warnings surface with the
  // first scene that drops the part, its failure with every such scene.
  std::vector<CollisionShape> part_shapes(parts.size());
  std::vector<std::exception_ptr> shape_failures(parts.size());
  std::vector<std::vector<std::string>> shape_warnings(parts.size());
  std::vector<int> first_dropping(parts.size(), -1);
  for (size_t i = 0; i < all.instances.size(); ++i) {
    const int s = jobs[job_of_instance[i]].scene;
    const ArrangementOptions& a = spec.scenes[s].arrangement;
    if (a.layout != Layout::kPile && a.pose != PoseMode::kDropped) continue;
    int& first = first_dropping[all.instances[i].part];
    if (first < 0 || s < first) first = s;
  }
  tbb::parallel_for(size_t{0}, parts.size(), [&](size_t p) {
    if (first_dropping[p] < 0) return;
    WarningCapture capture;
    try {
      part_shapes[p] = PartCollisionShape(parts[p], cache);
    } catch (...) {
      shape_failures[p] = std::current_exception();
    }
    shape_warnings[p] = capture.Take();
  });
  // Each scene's placement, every scene at once: a pile or a drop simulates one Bullet world on
  // one thread, so two piles take the time of one on two cores. Messages (the scene's own and the
  // warnings of what it calls, captured), errors and other exceptions follow in scene order.
  struct Placement {
    Arrangement arranged;
    std::vector<Drawn> distractor_record;
    size_t first_distractor = 0;
    std::vector<std::pair<bool, std::string>> messages;  // (a warning?, the text)
    std::string error;
    std::exception_ptr exception;  // anything else thrown
  };
  std::vector<Placement> placements(spec.scenes.size());
  tbb::parallel_for(size_t{0}, spec.scenes.size(), [&](size_t s) {
    std::vector<Instance> instances;
    std::vector<int> groups;
    for (size_t i = 0; i < all.instances.size(); ++i) {
      if (jobs[job_of_instance[i]].scene != static_cast<int>(s)) continue;
      instances.push_back(all.instances[i]);
      groups.push_back(job_of_instance[i]);
    }
    SceneRun& run = runs[s];
    run.scene = spec.look;
    Placement& placement = placements[s];
    std::vector<Drawn>& distractor_record = placement.distractor_record;
    size_t& first_distractor = placement.first_distractor;
    const SceneSpec& scene_spec = spec.scenes[s];
    Arrangement& arranged = placement.arranged;
    // Warnings of what the scene calls (Warn) are captured, and kept in order with its own.
    WarningCapture capture;
    const auto flush = [&] {
      for (std::string& w : capture.Take()) placement.messages.emplace_back(true, std::move(w));
    };
    const auto say = [&](bool warning, std::string text) {
      flush();
      placement.messages.emplace_back(warning, std::move(text));
    };
    // Warnings of the items of an inner parallel loop (captured per item, on whichever thread
    // ran it), in item order.
    const auto replay = [](const std::vector<std::vector<std::string>>& warnings) {
      for (const auto& item : warnings) {
        for (const std::string& w : item) Warn(w);
      }
    };
    try {
      const bool pile = scene_spec.arrangement.layout == Layout::kPile;
      const bool dropped = !pile && scene_spec.arrangement.pose == PoseMode::kDropped;
      std::vector<CollisionShape> shapes;
      if (pile || dropped) {
        // Collision shapes of the parts that fall, from the cache where it can.
        shapes.resize(parts.size());
        std::vector<size_t> used;
        for (const Instance& instance : instances)
          used.push_back(static_cast<size_t>(instance.part));
        std::sort(used.begin(), used.end());
        used.erase(std::unique(used.begin(), used.end()), used.end());
        for (size_t p : used) {
          if (first_dropping[p] == static_cast<int>(s)) {
            for (const std::string& w : shape_warnings[p]) Warn(w);
          }
          if (shape_failures[p]) std::rethrow_exception(shape_failures[p]);
          shapes[p] = part_shapes[p];
        }
      }
      ArrangementOptions arrangement = scene_spec.arrangement;
      if (scene_spec.container_file) arrangement.container.mesh = container_mesh[s];
      // Distractors: drawn for the scene, made (primitives) or taken (file and family parts),
      // given collision shapes, and dropped with (a pile) or onto (other layouts) the parts.
      const RandomizeSpec& randomize_spec =
          scene_spec.randomize ? *scene_spec.randomize : spec.randomize;
      std::vector<Part> with_distractors;
      std::vector<DistractorPick> picks;
      if (randomize_spec.draws.distractors) {
        std::string why;
        if (!randomize_spec.draws.Check(&why)) throw Error("randomize: " + why);
        std::vector<std::string> names;
        std::vector<int> sizes;
        for (const DistractorCandidate& c : distractor_candidates[s]) {
          names.push_back(c.name);
          sizes.push_back(c.kind == DistractorObject::Kind::kBox        ? 3
                          : c.kind == DistractorObject::Kind::kCylinder ? 2
                          : c.kind == DistractorObject::Kind::kSphere   ? 1
                                                                        : 0);
        }
        picks = DrawDistractors(randomize_spec.draws, s, names, sizes, &distractor_record);
      }
      if (!picks.empty()) {
        with_distractors = parts;
        std::vector<Part> made(picks.size());
        std::vector<std::vector<std::string>> made_warnings(picks.size());
        tbb::parallel_for(size_t{0}, picks.size(), [&](size_t k) {
          WarningCapture made_capture;
          const DistractorCandidate& c = distractor_candidates[s][picks[k].object];
          const Eigen::Vector3d& size = picks[k].size_mm;
          const std::string name = "distractor " + std::to_string(k) + " (" + c.name + ")";
          switch (c.kind) {
            case DistractorObject::Kind::kBox:
              made[k] = MakePart(name, MakeBox(size.x(), size.y(), size.z()), spec.tessellation);
              break;
            case DistractorObject::Kind::kCylinder:
              made[k] = MakePart(name, MakeCylinder(0.5 * size.x(), size.y()), spec.tessellation);
              break;
            case DistractorObject::Kind::kSphere:
              made[k] = MakePart(name, MakeSphere(0.5 * size.x()), spec.tessellation);
              break;
            case DistractorObject::Kind::kSource:
              made[k] = c.part;
              made[k].name = name;
              break;
          }
          made_warnings[k] = made_capture.Take();
        });
        replay(made_warnings);
        shapes.resize(parts.size() + picks.size());
        for (size_t k = 0; k < picks.size(); ++k) {
          arrangement.distractors.push_back(static_cast<int>(with_distractors.size()));
          with_distractors.push_back(std::move(made[k]));
          // Primitives: their hulls; a ball needs more corners than the default 32 to stay within
          // 0.5 mm of its surface (a 24 mm ball sank 1.4 mm into the floor with 32). Every
          // contact scans them all, so cylinders take 64 and boxes have their 8.
          const DistractorObject::Kind kind = distractor_candidates[s][picks[k].object].kind;
          if (kind != DistractorObject::Kind::kSource) {
            CollisionOptions round;
            round.max_corners = kind == DistractorObject::Kind::kSphere ? 128 : 64;
            shapes[parts.size() + k] = MakeCollisionShape(with_distractors.back(), round);
          }
        }
        // Collision shapes of every part that falls or is fallen on (cached where they can be).
        std::vector<size_t> need;
        for (const Instance& instance : instances)
          need.push_back(static_cast<size_t>(instance.part));
        for (int d : arrangement.distractors) need.push_back(static_cast<size_t>(d));
        std::sort(need.begin(), need.end());
        need.erase(std::unique(need.begin(), need.end()), need.end());
        // A flat part (no volume) has no shape: distractors do not land on it.
        std::vector<std::string> errors(need.size());
        std::vector<std::vector<std::string>> need_warnings(need.size());
        tbb::parallel_for(size_t{0}, need.size(), [&](size_t k) {
          if (!shapes[need[k]].pieces.empty()) return;
          WarningCapture need_capture;
          try {
            shapes[need[k]] = PartCollisionShape(with_distractors[need[k]], cache);
          } catch (const Error& e) {
            errors[k] = e.what();
          }
          need_warnings[k] = need_capture.Take();
        });
        replay(need_warnings);
        for (size_t k = 0; k < need.size(); ++k) {
          if (!errors[k].empty() && need[k] >= parts.size()) throw Error(errors[k]);
        }
        arrangement.distractor_seed = DistractorDropSeed(randomize_spec.draws, s);
      }
      const std::vector<Part>& arranged_parts = picks.empty() ? parts : with_distractors;
      if (!scene_spec.physics_rules.empty()) {
        // Each part's physics: the first rule matching it (by the source of its first instance);
        // distractors take the scene's.
        arrangement.part_physics.assign(arranged_parts.size(), arrangement.physics);
        std::vector<bool> done(parts.size(), false);
        for (size_t i = 0; i < instances.size(); ++i) {
          const auto p = static_cast<size_t>(instances[i].part);
          if (done[p]) continue;
          done[p] = true;
          for (const PhysicsRule& rule : scene_spec.physics_rules) {
            if (RuleMatches(rule, parts[p].name, *jobs[groups[i]].source)) {
              arrangement.part_physics[p] = rule.physics;
              break;
            }
          }
        }
      }
      if (dropped) {
        arranged = Arrange(arranged_parts, instances, arrangement, groups, &shapes);
        if (!arranged.restless.empty()) {
          std::ostringstream m;
          m << "scene '" << scene_spec.name << "': " << arranged.restless.size()
            << " dropped parts still moving after settle_time ("
            << scene_spec.arrangement.settle_time_s
            << " s, simulated): raise settle_time; each is put on the stable face nearest its "
               "last pose (or left as it was, tilted more than 5 degrees from any)";
          say(true, m.str());
        }
      } else if (pile) {
        arranged = Arrange(arranged_parts, instances, arrangement, groups, &shapes);
        std::ostringstream m;
        m << "scene '" << scene_spec.name << "': " << arranged.instances.size()
          << " parts dropped; ";
        if (arranged.restless.empty()) {
          m << "at rest after " << arranged.settle_seconds << " s (simulated)";
          say(false, m.str());
        } else {
          m << arranged.restless.size() << " still moving after settle_time ("
            << scene_spec.arrangement.settle_time_s
            << " s, simulated): raise settle_time, or drop fewer parts";
          say(true, m.str());
        }
        if (!arranged.escaped.empty()) {
          say(true, "scene '" + scene_spec.name + "': " + std::to_string(arranged.escaped.size()) +
                        " parts bounced out of the tote (they are kept where they landed)");
        }
        const Mesh tote = MakeContainerMesh(arrangement.container);
        if (!tote.empty()) {
          Scene::Fixture fixture;
          fixture.name = scene_spec.container_file
                             ? scene_spec.container_file->path.filename().string()
                             : "tote";
          fixture.mesh = tote;
          fixture.color = scene_spec.container_color;
          Eigen::Vector3f linear;
          for (int c = 0; c < 3; ++c) linear[c] = SrgbToLinear(fixture.color[c]);
          fixture.material = scene_spec.container_material
                                 ? *scene_spec.container_material
                                 : Scene::DefaultMaterial(scene_spec.container_color);
          if (fixture.material.base_from_part) fixture.material.surface.base_color = linear;
          run.scene.fixtures.push_back(std::move(fixture));
        }
      } else {
        arranged = Arrange(arranged_parts, instances, arrangement, groups,
                           picks.empty() ? nullptr : &shapes);
      }
      // The distractors as fixtures: drawn and traced, occluding, never labelled.
      first_distractor = run.scene.fixtures.size();
      for (size_t k = 0; k < arranged.distractors.size(); ++k) {
        const Instance& d = arranged.distractors[k];
        Scene::Fixture fixture;
        fixture.name = arranged_parts[d.part].name;
        fixture.mesh = arranged_parts[d.part].mesh;
        fixture.mesh.Transform(d.world_from_model);
        fixture.color = picks[k].color;
        fixture.material = Scene::DefaultMaterial(fixture.color);
        run.scene.fixtures.push_back(std::move(fixture));
        const Eigen::Quaterniond q(d.world_from_model.linear());
        const Eigen::Vector3d t = d.world_from_model.translation();
        distractor_record.push_back({"distractor." + std::to_string(k) + ".pose",
                                     {t.x(), t.y(), t.z(), q.w(), q.x(), q.y(), q.z()},
                                     ""});
      }
      if (!arranged.distractors.empty() && !pile) {
        std::ostringstream m;
        m << "scene '" << scene_spec.name << "': " << arranged.distractors.size()
          << " distractors dropped among the parts in " << arranged.distractor_seconds
          << " s (simulated)";
        say(false, m.str());
      }
      if (!arranged.escaped_distractors.empty()) {
        say(true, "scene '" + scene_spec.name +
                      "': " + std::to_string(arranged.escaped_distractors.size()) +
                      " distractors bounced out of the tote (they are kept where they landed)");
      }
      if (!arranged.restless_distractors.empty()) {
        say(true, "scene '" + scene_spec.name +
                      "': " + std::to_string(arranged.restless_distractors.size()) +
                      " distractors still moving after settle_time (" +
                      std::to_string(scene_spec.arrangement.settle_time_s) +
                      " s, simulated): they are kept where they were");
      }
    } catch (const Error& e) {
      placement.error = "scene '" + scene_spec.name + "': " + e.what();
    } catch (...) {
      placement.exception = std::current_exception();
    }
    flush();
  });
  for (size_t s = 0; s < spec.scenes.size(); ++s) {
    Placement& placement = placements[s];
    for (const auto& [warning, text] : placement.messages) warning ? Warn(text) : info(text);
    if (!placement.error.empty()) throw Error(placement.error);
    if (placement.exception) std::rethrow_exception(placement.exception);
    SceneRun& run = runs[s];
    const SceneSpec& scene_spec = spec.scenes[s];
    const Arrangement& arranged = placement.arranged;
    std::vector<Drawn>& distractor_record = placement.distractor_record;
    const size_t first_distractor = placement.first_distractor;
    run.scene.instances = arranged.instances;
    // The pbr mode's materials: the first rule matching the part's name, family and file.
    run.scene.materials.clear();
    run.scene.instance_material.assign(run.scene.instances.size(), -1);
    for (const MaterialRule& rule : spec.material_rules)
      run.scene.materials.push_back(rule.material);
    if (spec.default_material) run.scene.materials.push_back(*spec.default_material);
    for (size_t i = 0; i < run.scene.instances.size(); ++i) {
      const PartSource& source = *jobs[arranged.group[i]].source;
      const std::string& name = parts[run.scene.instances[i].part].name;
      for (size_t r = 0; r < spec.material_rules.size(); ++r) {
        const MaterialRule& rule = spec.material_rules[r];
        if (RuleMatches(rule, name, source)) {
          run.scene.instance_material[i] = static_cast<int>(r);
          used_rules[r] = true;
          break;
        }
      }
      if (run.scene.instance_material[i] < 0 && spec.default_material)
        run.scene.instance_material[i] = static_cast<int>(spec.material_rules.size());
      const int m = run.scene.instance_material[i];
      if (m >= 0 && run.scene.materials[m].texture.projection == Texture::Projection::kUv &&
          !parts[run.scene.instances[i].part].mesh.has_uvs()) {
        const size_t r = static_cast<size_t>(m);
        const std::string at =
            r < spec.material_rules.size()
                ? (spec.material_rules[r].where.empty() ? ""
                                                        : spec.material_rules[r].where + ": ") +
                      "materials.assign[" + std::to_string(r) + "]"
                : "materials.default";
        throw Error(at + ": texture projection 'uv', but part '" + name +
                    "' has no texture coordinates (only meshes such as OBJ or glTF files carry "
                    "them): use 'auto' or 'triplanar'");
      }
    }
    // Domain randomisation: the scene's own (or the recipe's), each instance's first matching
    // part rule.
    const RandomizeSpec& randomize = scene_spec.randomize ? *scene_spec.randomize : spec.randomize;
    run.randomization = randomize.draws;
    {
      std::string why;
      if (!run.randomization.Check(&why))
        throw Error("scene '" + scene_spec.name + "': randomize: " + why);
    }
    run.randomization.first_distractor = first_distractor;
    run.randomization.scene_record = std::move(distractor_record);
    run.randomization.instance_rule.assign(run.scene.instances.size(), -1);
    run.randomization.instance_part.clear();
    for (size_t i = 0; i < run.scene.instances.size(); ++i) {
      const PartSource& source = *jobs[arranged.group[i]].source;
      const int part = run.scene.instances[i].part;
      run.randomization.instance_part.push_back(part);
      for (size_t r = 0; r < randomize.part_rules.size(); ++r) {
        if (RuleMatches(randomize.part_rules[r], parts[part].name, source)) {
          run.randomization.instance_rule[i] = static_cast<int>(r);
          break;
        }
      }
    }
    // Rules matching no part: a scene's own are reported for it; the recipe's once, below.
    for (size_t r = 0; r < randomize.part_rules.size(); ++r) {
      const std::vector<int>& rules = run.randomization.instance_rule;
      const bool used = std::find(rules.begin(), rules.end(), static_cast<int>(r)) != rules.end();
      if (!scene_spec.randomize) {
        used_randomize_rules[r] = used_randomize_rules[r] || used;
      } else if (!used) {
        const std::string& where = randomize.part_rules[r].where;
        Warn((where.empty() ? "" : where + ": ") + "scene '" + scene_spec.name +
             "': randomize.parts[" + std::to_string(r) + "] matches no part");
      }
    }
    recipe_randomize_used = recipe_randomize_used || !scene_spec.randomize;
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
  for (size_t r = 0; r < used_rules.size(); ++r) {
    if (!used_rules[r]) Warn("materials.assign[" + std::to_string(r) + "] matches no part");
  }
  for (size_t r = 0; recipe_randomize_used && r < used_randomize_rules.size(); ++r) {
    if (!used_randomize_rules[r]) {
      const std::string& where = spec.randomize.part_rules[r].where;
      Warn((where.empty() ? "" : where + ": ") + "randomize.parts[" + std::to_string(r) +
           "] matches no part");
    }
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
    Json entry = {{"id", jobs[j].id},
                  {"scene_id", jobs[j].scene},
                  {"scene", spec.scenes[jobs[j].scene].name}};
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
    prepared.randomization.push_back(std::move(run.randomization));
  }
  prepared.parts = std::move(all.parts);
  prepared.classes = classes;
  return prepared;
}

}  // namespace cadsynth
