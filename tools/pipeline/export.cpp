#include "tools/pipeline/export.h"

#include <unistd.h>

#include <sstream>
#include <system_error>

#include <tbb/parallel_for.h>

#include "cad/core/error.h"
#include "cad/step.h"
#include "variants/families.h"

namespace cadsynth {

std::vector<VariantListing> ListVariants(const RunSpec& spec) {
  std::vector<VariantListing> list;
  for (const SceneSpec& scene : spec.scenes) {
    for (size_t e = 0; e < scene.sources.size(); ++e) {
      const PartSource& source = scene.sources[e];
      const std::string base = scene.name + "/" + std::to_string(e) + "/";
      if (source.kind == PartSource::Kind::kFile) {
        list.push_back({base + source.path.filename().string(), "", source.path.string(), {}});
        continue;
      }
      for (size_t v = 0; v < source.variants.size(); ++v) {
        list.push_back({base + source.family + "/" + std::to_string(v),
                        source.family,
                        DescribeParams(source.variants[v], FindFamily(source.family)),
                        {}});
      }
    }
  }
  return list;
}

std::vector<VariantListing> ExportVariants(const RunSpec& spec, const std::filesystem::path& dir,
                                           bool overwrite) {
  const std::filesystem::path target = std::filesystem::absolute(dir).lexically_normal();
  std::error_code ec;
  if (std::filesystem::exists(target, ec) && !overwrite) {
    throw Error(target.string() + ": already exists (pass --overwrite to replace it)");
  }
  struct Job {
    const PartSource* source;
    size_t variant;
    VariantListing listing;
  };
  std::vector<Job> jobs;
  size_t index = 0;
  const std::vector<VariantListing> all = ListVariants(spec);
  for (const SceneSpec& scene : spec.scenes) {
    for (const PartSource& source : scene.sources) {
      if (source.kind == PartSource::Kind::kFile) {
        ++index;
        continue;
      }
      for (size_t v = 0; v < source.variants.size(); ++v)
        jobs.push_back({&source, v, all[index++]});
    }
  }
  if (jobs.empty()) throw Error("the recipe has no family variants to export");

  std::filesystem::create_directories(target.parent_path(), ec);
  std::string hidden = ".";
  hidden.append(target.filename().string()).append(".partial-").append(std::to_string(::getpid()));
  const std::filesystem::path staging = target.parent_path() / hidden;
  std::filesystem::remove_all(staging, ec);
  std::filesystem::create_directories(staging, ec);
  if (ec) throw Error(staging.string() + ": cannot create folder: " + ec.message());

  std::vector<std::string> errors(jobs.size());
  tbb::parallel_for(size_t{0}, jobs.size(), [&](size_t j) {
    Job& job = jobs[j];
    try {
      ImportOptions options;
      options.tessellation = spec.tessellation;
      const Assembly a =
          BuildVariant(*FindFamily(job.source->family), job.source->variants[job.variant], options);
      std::vector<StepComponent> components;
      for (size_t p = 0; p < a.parts.size(); ++p) {
        if (a.parts[p].brep.IsNull())
          throw Error("part '" + a.parts[p].name + "' has no exact geometry to export");
        StepComponent c{a.parts[p].name, a.parts[p].brep, {}, a.parts[p].color};
        for (const Instance& i : a.instances) {
          if (i.part == static_cast<int>(p))
            c.placements.push_back(i.world_from_model * a.parts[p].cad_from_model.inverse());
        }
        components.push_back(std::move(c));
      }
      std::string name = job.listing.id;
      for (char& c : name) c = (c == '/' || c == ' ') ? '_' : c;
      job.listing.step = target / (name + ".step");
      WriteStep(staging / (name + ".step"), a.name, components);
    } catch (const Error& e) {
      errors[j] = (job.source->where.empty() ? "" : job.source->where + ": ") + job.listing.id +
                  " (" + job.listing.params + "): " + e.what();
    }
  });
  for (const std::string& error : errors) {
    if (!error.empty()) {
      std::filesystem::remove_all(staging, ec);
      throw Error(error);
    }
  }
  if (std::filesystem::exists(target, ec)) std::filesystem::remove_all(target, ec);
  std::filesystem::rename(staging, target, ec);
  if (ec) {
    std::filesystem::remove_all(staging, ec);
    throw Error(target.string() + ": cannot move the exported files into place: " + ec.message());
  }
  std::vector<VariantListing> out;
  for (const Job& job : jobs) out.push_back(job.listing);
  return out;
}

}  // namespace cadsynth
