// Prepare's part stages (prepare_stages.h): every source read and built (with the cache), the
// containers and distractor objects alike, the parts gathered into one list, their symmetries,
// repeated shapes merged, names made unique, hulls computed and classes assigned.
#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>

#include <tbb/parallel_for.h>

#include "cad/assembly.h"
#include "cad/core/error.h"
#include "cad/core/schema.h"
#include "cad/hull.h"
#include "cad/import.h"
#include "cad/part_cache.h"
#include "cad/symmetry.h"
#include "dataset/file_io.h"
#include "tools/pipeline/prepare_stages.h"
#include "variants/families.h"

namespace cadsynth::prepare_stages {
namespace {

// Inputs large enough to announce before working on them.
constexpr uintmax_t kLargeFileBytes = 50u << 20;
constexpr size_t kLargeMeshVertices = 1000000;

// The options an import or variant depends on, into a cache key.
void HashOptions(KeyHasher* hasher, const ImportOptions& options) {
  hasher->Fields(options.tessellation);
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

// Builds every job in parallel.
void BuildAll(const Context& context, std::vector<Job>* jobs) {
  tbb::parallel_for(size_t{0}, jobs->size(), [&](size_t j) {
    Build(context.spec, context.cache, context.reader, &(*jobs)[j]);
  });
}

// The jobs' warnings, and the first error, in recipe order.
void ReportJobs(const std::vector<Job>& jobs) {
  for (const Job& job : jobs) {
    for (const std::string& warning : job.warnings) Warn(warning);
    if (!job.error.empty()) throw Error(job.error);
  }
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

// Everything that decides what a distractor source builds: its place in the recipe, file, unit,
// family and every variant's parameters.
std::string DistractorKey(const DistractorObject& o) {
  std::ostringstream key;
  key << o.where << "|" << o.source.path.string() << "|" << o.source.unit << "|"
      << o.source.encoding << "|" << o.source.family;
  for (const ParamValues& v : o.source.variants) key << "|" << ParamsJson(v).dump();
  return key.str();
}

// The jobs of the distractor sources of every scene that draws distractors, each source once
// (`jobs_of`: by DistractorKey, its jobs).
std::vector<Job> DistractorJobs(const RunSpec& spec,
                                std::map<std::string, std::vector<size_t>>* jobs_of) {
  std::vector<Job> sources;
  for (size_t s = 0; s < spec.scenes.size(); ++s) {
    const RandomizeSpec& r = spec.scenes[s].randomize ? *spec.scenes[s].randomize : spec.randomize;
    if (!r.draws.distractors) continue;
    for (const DistractorObject& object : r.distractor_objects) {
      if (object.kind != DistractorObject::Kind::kSource || jobs_of->count(DistractorKey(object)))
        continue;
      std::vector<size_t>& mine = (*jobs_of)[DistractorKey(object)];
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
  return sources;
}

// The recipe's list of a part's symmetries, each entry measured on its own (its worst deviation
// into `entry_deviation`, to name the entry that does not hold), then all of them together.
DetectedSymmetries MeasureListedSymmetries(const Part& part, const PartSource& given,
                                           const SymmetryOptions& options,
                                           std::vector<double>* entry_deviation) {
  // The list is in the part's CAD frame; an axis without a point passes through the
  // surface's centroid.
  const Eigen::Vector3d centre = MeasureSymmetries(part.mesh, {}, options).centre;
  const Eigen::Isometry3d model_from_cad = part.cad_from_model.inverse();
  Symmetries all_given;
  for (const PartSource::GivenSymmetry& g : given.given_symmetries) {
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
    entry_deviation->push_back(worst);
    all_given.discrete.insert(all_given.discrete.end(), one.discrete.begin(), one.discrete.end());
    all_given.continuous.insert(all_given.continuous.end(), one.continuous.begin(),
                                one.continuous.end());
  }
  return MeasureSymmetries(part.mesh, all_given, options);
}

// Every listed symmetry, and every product of them, must hold within the tolerance.
void CheckListedSymmetries(const std::string& part_name,
                           const std::vector<PartSource::GivenSymmetry>& list,
                           const DetectedSymmetries& found,
                           const std::vector<double>& entry_deviation) {
  const auto mm = [](double v) {
    std::ostringstream text;
    text.precision(3);
    text << v << " mm";
    return text.str();
  };
  for (size_t e = 0; e < list.size(); ++e) {
    if (entry_deviation[e] > found.tolerance_mm) {
      throw Error(list[e].where + ": symmetry: this turn moves the surface of '" + part_name +
                  "' up to " + mm(entry_deviation[e]) + " off itself, beyond the " +
                  "tolerance of " + mm(found.tolerance_mm) +
                  " (raise symmetry_tolerance to accept it)");
    }
  }
  double worst = 0;
  for (double d : found.discrete_deviation_mm) worst = std::max(worst, d);
  if (worst > found.tolerance_mm) {
    throw Error(list[0].where + ": symmetry: the listed turns combined move the surface of '" +
                part_name + "' up to " + mm(worst) + " off itself, beyond the tolerance of " +
                mm(found.tolerance_mm) + " (are the axes through the same point?)");
  }
}

}  // namespace

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

std::vector<Job> BuildParts(const Context& context) {
  const RunSpec& spec = context.spec;
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
      context.info("reading " + job.source->path.string() + " (" + std::to_string(bytes >> 20) +
                   " MB)");
    }
  }
  // Many sources (a family grid): a line at every tenth built.
  std::atomic<size_t> built{0};
  std::mutex info_mutex;
  tbb::parallel_for(size_t{0}, jobs.size(), [&](size_t j) {
    Build(spec, context.cache, context.reader, &jobs[j]);
    const size_t n = ++built, total = jobs.size();
    if (total >= 20 && (n * 10 / total) != ((n - 1) * 10 / total)) {
      std::lock_guard<std::mutex> lock(info_mutex);
      context.info("built " + std::to_string(n) + " of " + std::to_string(total) +
                   " parts and variants");
    }
  });
  ReportJobs(jobs);
  return jobs;
}

// Containers from files (container type: file): read like part files (and cached alike), all
// their instances one mesh, centred over the origin and standing on the floor.
std::vector<Mesh> BuildContainers(const Context& context) {
  const RunSpec& spec = context.spec;
  std::vector<Mesh> container_mesh(spec.scenes.size());
  std::vector<Job> containers;
  for (size_t s = 0; s < spec.scenes.size(); ++s) {
    if (const auto& file = spec.scenes[s].container_file) {
      containers.push_back({static_cast<int>(s), &*file, 0, file->path.string(), {}, {}, {}});
    }
  }
  BuildAll(context, &containers);
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
    context.info(line.str());
  }
  return container_mesh;
}

// Distractor objects (randomize.distractors.objects) of the recipe and of scenes with their
// own: primitives by name, and every distinct part of each file or family variant (read like
// part files, and cached alike). An object listed once but inherited by several scenes
// (the same recipe place) is read once.
std::vector<std::vector<DistractorCandidate>> BuildDistractorObjects(const Context& context) {
  const RunSpec& spec = context.spec;
  std::vector<std::vector<DistractorCandidate>> distractor_candidates(spec.scenes.size());
  std::map<std::string, std::vector<size_t>> jobs_of;  // by where and what: its jobs
  std::vector<Job> sources = DistractorJobs(spec, &jobs_of);
  BuildAll(context, &sources);
  ReportJobs(sources);
  for (size_t s = 0; s < spec.scenes.size(); ++s) {
    const RandomizeSpec& r = spec.scenes[s].randomize ? *spec.scenes[s].randomize : spec.randomize;
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
      for (size_t j : jobs_of[DistractorKey(object)]) {
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
  return distractor_candidates;
}

std::vector<SymmetryCheck> GatherParts(const Context& context, PrepareState* state) {
  Assembly& all = state->all;
  std::vector<SymmetryCheck> detect;  // parts without declared symmetries, to look for them
  for (size_t j = 0; j < state->jobs.size(); ++j) {
    Assembly& a = state->jobs[j].assembly;
    const PartSource& source = *state->jobs[j].source;
    if (source.kind == PartSource::Kind::kFile) {
      std::ostringstream line;
      line << "read " << source.path.string() << " (" << a.format << "): '" << a.name << "', unit "
           << (a.length_unit.empty() ? "?" : a.length_unit) << ", " << a.parts.size() << " parts, "
           << a.instances.size() << " instances";
      context.info(line.str());
    }
    const int offset = static_cast<int>(all.parts.size());
    for (Part& part : a.parts) {
      state->label_of_part.push_back(source.one_class ? source.family : std::string());
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
      state->job_of_instance.push_back(static_cast<int>(j));
    }
  }
  return detect;
}

// What a part's symmetries on its mesh depend on: the mesh, the options (tolerances, limits, the
// B-rep's axes of revolution) and a recipe's list with the frame it is given in.
static std::optional<CacheKey> SymmetryKey(const PartCache* cache, const Part& part,
                                           const SymmetryOptions& options,
                                           const PartSource* given) {
  if (cache == nullptr) return std::nullopt;
  KeyHasher hasher;
  cache->Start(&hasher, "symmetry 1");
  hasher.Geometry(part.mesh);
  hasher.Value(options.tolerance_mm).Value(options.deviation_mm);
  hasher.Value(options.max_order).Value(options.max_points);
  hasher.Value<uint64_t>(options.axis_hints.size());
  for (const SymmetryOptions::Line& line : options.axis_hints)
    hasher.Value(line.point).Value(line.direction);
  hasher.Value<uint8_t>(given != nullptr);
  if (given != nullptr) {
    hasher.Value(part.cad_from_model.matrix());
    hasher.Value<uint64_t>(given->given_symmetries.size());
    for (const PartSource::GivenSymmetry& g : given->given_symmetries) {
      hasher.Value(g.axis).Value(g.order).Value<uint8_t>(g.through.has_value());
      if (g.through) hasher.Value(*g.through);
    }
  }
  return hasher.Key();
}

// Symmetries of the parts that declare none (imported files), found on their meshes, or as
// the recipe lists them, measured on the meshes; both kept in the part cache.
void FindSymmetries(const Context& context, const std::vector<SymmetryCheck>& detect,
                    std::vector<Part>* parts) {
  std::vector<DetectedSymmetries> found(detect.size());
  // Per listed entry, its own worst deviation (to name the entry that does not hold).
  std::vector<std::vector<double>> entry_deviation(detect.size());
  std::vector<std::string> failure(detect.size());  // why nothing could be measured
  tbb::parallel_for(size_t{0}, detect.size(), [&](size_t k) {
    const Part& part = (*parts)[detect[k].part];
    if (part.mesh.triangles.empty()) {
      failure[k] = "its mesh has no triangles";
      return;
    }
    try {
      const SymmetryOptions options = PartSymmetryOptions(part, detect[k].tolerance_mm);
      const std::optional<CacheKey> key =
          SymmetryKey(context.cache, part, options, detect[k].given);
      bool cached = false;
      if (key) {
        if (const std::optional<std::string> bytes = context.cache->Load("symmetry", *key)) {
          try {
            found[k] = DecodeDetectedSymmetries(*bytes, &entry_deviation[k]);
            cached = true;
          } catch (const Error&) {  // damaged: measured again below
            entry_deviation[k].clear();
          }
        }
      }
      if (!cached) {
        if (detect[k].given == nullptr) {
          found[k] = DetectSymmetries(part.mesh, options);
        } else {
          found[k] = MeasureListedSymmetries(part, *detect[k].given, options, &entry_deviation[k]);
        }
        if (key) {
          context.cache->Store("symmetry", *key,
                               EncodeDetectedSymmetries(found[k], entry_deviation[k]));
        }
      }
      // On the exact B-rep, which the key does not cover (the mesh and the options do).
      CompareBrepFaces(part, &found[k]);
    } catch (const Error& e) {
      failure[k] = e.what();  // reported below, in order
    }
  });
  for (size_t k = 0; k < detect.size(); ++k) {
    Part& part = (*parts)[detect[k].part];
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
      CheckListedSymmetries(part.name, detect[k].given->given_symmetries, found[k],
                            entry_deviation[k]);
    }
    part.symmetries = found[k].symmetries;
    if (part.symmetries.empty()) continue;
    context.info("symmetries of '" + part.name + "'" + (detect[k].given ? " (as listed)" : "") +
                 ": " + DescribeSymmetries(found[k]));
  }
}

void ReportFamilies(const Context& context) {
  for (const SceneSpec& scene : context.spec.scenes) {
    for (const PartSource& source : scene.sources) {
      if (source.kind == PartSource::Kind::kFamily) {
        context.info("built " + std::to_string(source.variants.size()) + " variant(s) of " +
                     source.family + " for scene '" + scene.name + "'");
      }
    }
  }
}

// The same shape from several files, variants or scenes is one object.
void MergeRepeatedShapes(const Context& context, PrepareState* state) {
  Assembly& all = state->all;
  std::vector<int> first_instance_part(all.instances.size());
  for (size_t i = 0; i < all.instances.size(); ++i) first_instance_part[i] = all.instances[i].part;
  const size_t merged = MergeIdenticalParts(
      &all, 2.0 * context.spec.tessellation.linear_deflection_mm + 1e-3, context.cache);
  if (merged > 0)
    context.info("merged " + std::to_string(merged) + " parts that repeat the shape of another");
  std::vector<std::string> labels(all.parts.size());
  for (size_t i = 0; i < all.instances.size(); ++i) {
    std::string& label = labels[all.instances[i].part];
    if (label.empty()) label = state->label_of_part[first_instance_part[i]];
  }
  state->label_of_part = std::move(labels);
}

// Two objects of one name (some exporters call every body "SOLID") would be two COCO
// categories and two classes of one name: the later ones get "_2", "_3", ...
void RenameRepeatedNames(std::vector<Part>* parts) {
  std::set<std::string> used;
  for (const Part& part : *parts) used.insert(part.name);
  std::set<std::string> taken;
  for (Part& part : *parts) {
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
void ComputeHulls(const Context& context, std::vector<Part>* parts) {
  for (const Part& part : *parts) {
    if (part.mesh.num_vertices() >= kLargeMeshVertices) {
      context.info("convex hull and diameter of '" + part.name + "' (" +
                   std::to_string(part.mesh.num_vertices()) + " vertices)");
    }
  }
  tbb::parallel_for(size_t{0}, parts->size(), [&](size_t i) {
    (*parts)[i].hull = PartHull((*parts)[i].mesh, context.cache);
  });
}

std::vector<ObjectClass> AssignPartClasses(const Context& context, const PrepareState& state) {
  const std::vector<Part>& parts = state.all.parts;
  std::vector<std::string> names, empty_groups;
  for (const Part& part : parts) names.push_back(part.name);
  std::vector<ObjectClass> classes =
      AssignClasses(names, state.label_of_part, context.spec.class_groups, &empty_groups);
  for (const std::string& group : empty_groups) Warn("class '" + group + "' matches no part");
  for (size_t i = 0; i < parts.size(); ++i) {
    const Eigen::Vector3d size = parts[i].mesh.Bounds().sizes();
    std::ostringstream p;
    p.precision(4);
    p << "  obj_id " << i + 1 << ": '" << parts[i].name << "' " << size.x() << " x " << size.y()
      << " x " << size.z() << " mm, " << parts[i].mesh.num_triangles() << " triangles, class "
      << classes[i].id << " '" << classes[i].name << "'";
    context.info(p.str());
  }
  return classes;
}

}  // namespace cadsynth::prepare_stages
