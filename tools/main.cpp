// The cadsynth command line. Owns threads (one tbb::global_control), logging and exit codes.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <tbb/global_control.h>
#include <CLI/CLI.hpp>

#include "cad/core/error.h"
#include "cad/core/util.h"
#include "cad/part_cache.h"
#include "dataset/file_io.h"
#include "dataset/manifest.h"
#include "dataset/preview.h"
#include "dataset/verify.h"
#include "recipes/recipe.h"
#include "recipes/recipe_schema.h"
#include "tools/pipeline/eval.h"
#include "tools/pipeline/export.h"
#include "tools/pipeline/generate.h"
#include "tools/pipeline/guarded_import.h"
#include "tools/pipeline/inspect.h"
#include "tools/pipeline/progress.h"
#include "tools/pipeline/report.h"
#include "tools/pipeline/sensor_test.h"
#include "tools/pipeline/shards.h"

namespace {

struct UsageError {
  std::string what;
};

// One error line stays readable: a message that quotes a user's 5 MB name keeps its start and end.
std::string Shortened(const std::string& message) {
  constexpr size_t kMax = 2000;
  if (message.size() <= kMax) return message;
  return message.substr(0, kMax / 2) + " [... " + std::to_string(message.size() - kMax) +
         " characters left out ...] " + message.substr(message.size() - kMax / 2);
}

// What a subcommand was given on the command line; filled by CLI11, read by Run*.
struct Args {
  // generate
  std::string recipe, output, shard, progress = "auto", cache;
  bool overwrite = false, strict = false, quiet = false, help_recipe = false, recipe_schema = false,
       no_cache = false;
  int threads = 0, shards = 0;
  // merge, preview, verify, report
  std::string dir;
  // inspect
  std::string file, unit, encoding;
  double deflection_mm = cadsynth::ImportOptions{}.tessellation.linear_deflection_mm;
  bool json = false;
  // variants
  std::string export_dir;
  bool families = false;
  // eval
  std::string results, json_file;
  // preview
  std::string frames, versus;
  // eval, preview: a multi-sensor dataset's sensor
  std::string sensor;
  int count = 4, width = 320, grasps = 10;
  // verify, report
  std::string certificate, data_file;
  bool verify_first = false;
  int pixels = cadsynth::VerifyOptions{}.pixels_per_image;
  // sensor-test
  std::string material;
  std::vector<double> distances_mm, tilts_deg;
  double albedo = -1.0, roi = 0.8, step_mm = 100.0;
  int test_frames = 10;
  bool check = false, list = false;
};

// This executable, to read CAD and mesh files in child processes (a reader that crashes or hangs
// on a file then ends in an error, not in a signal).
std::filesystem::path SelfExecutable() {
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path() : self;
}

int RunGenerate(const Args& a) {
  if (a.help_recipe) {
    std::cout << cadsynth::RecipeReference();
    return 0;
  }
  if (a.recipe_schema) {
    std::cout << cadsynth::RecipeJsonSchema();
    return 0;
  }
  std::optional<cadsynth::ShardSpec> shard;
  std::string shard_source;
  if (a.shards != 0 && a.shard != "auto") {
    throw UsageError{"--shards N goes with --shard auto (with --shard I/N the count is N)"};
  }
  if (!a.shard.empty()) {
    try {
      if (a.shard == "auto") {
        const cadsynth::SchedulerShard found = cadsynth::ShardFromScheduler(
            [](const char* name) { return std::getenv(name); }, a.shards);
        shard = found.shard;
        shard_source = found.source;
      } else {
        shard = cadsynth::ParseShard(a.shard);
      }
    } catch (const cadsynth::Error& e) {
      throw UsageError{e.what()};
    }
  }
  std::unique_ptr<tbb::global_control> thread_limit;
  if (a.threads > 0) {
    thread_limit = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, static_cast<size_t>(a.threads));
  }

  const cadsynth::RunSpec spec =
      !a.recipe.empty() ? cadsynth::LoadRecipe(a.recipe) : cadsynth::DefaultRunSpec();
  cadsynth::GenerateOptions options;
  options.output = !a.output.empty() ? std::filesystem::path(a.output)
                                     : (!spec.output.empty() ? spec.output : "cadsynth_dataset");
  options.overwrite = a.overwrite;
  options.strict = a.strict;
  options.shard = shard;
  options.reader = SelfExecutable();
  if (!a.no_cache) {
    options.cache = !a.cache.empty() ? std::optional<std::filesystem::path>(a.cache)
                                     : cadsynth::PartCache::DefaultDirectory();
  }
  if (!a.quiet) {
    options.info = [](const std::string& line) { std::cout << line << "\n" << std::flush; };
    if (!shard_source.empty()) options.info("shard " + shard->Name() + " from " + shard_source);
  }
  if (!a.quiet || a.progress == "json") {
    using Mode = cadsynth::ProgressReporter::Mode;
    const Mode mode = a.progress == "json"           ? Mode::kJson
                      : a.progress == "bar"          ? Mode::kBar
                      : a.progress == "lines"        ? Mode::kLines
                      : ::isatty(STDERR_FILENO) != 0 ? Mode::kBar
                                                     : Mode::kLines;
    auto reporter = std::make_shared<cadsynth::ProgressReporter>(mode, stderr);
    if (shard) reporter->SetShard(shard->Name());
    options.progress = [reporter](size_t done, size_t total) { reporter->Update(done, total); };
    options.stage_progress = [reporter](const cadsynth::StageReport& report) {
      reporter->Stage(report);
    };
  }
  const cadsynth::GenerateSummary summary = cadsynth::Generate(spec, options);
  if (summary.skipped_empty + summary.skipped_sparse > 0) {
    std::printf("skipped %zu views: %zu showed no object, %zu fewer than %d object pixels\n",
                summary.skipped_empty + summary.skipped_sparse, summary.skipped_empty,
                summary.skipped_sparse, spec.min_visible_pixels);
  }
  const size_t rendered = summary.frames - summary.resumed;
  std::printf(
      "wrote %zu frame%s (%zu scene%s) of %zu object%s (%zu instance%s)%s to %s in %.1f s (%s "
      "overall)\n",
      summary.frames, summary.frames == 1 ? "" : "s", summary.scenes,
      summary.scenes == 1 ? "" : "s", summary.objects, summary.objects == 1 ? "" : "s",
      summary.instances, summary.instances == 1 ? "" : "s",
      shard ? (" as shard " + shard->Name()).c_str() : "",
      std::filesystem::absolute(options.output).lexically_normal().c_str(), summary.seconds,
      cadsynth::FormatRate(rendered, summary.seconds).c_str());
  return 0;
}

int RunMerge(const Args& a) {
  const cadsynth::MergeSummary summary = cadsynth::Merge(a.dir);
  std::printf("merged %d shard%s into %s: %zu frames in %zu scene%s, %.1f s\n", summary.shards,
              summary.shards == 1 ? "" : "s",
              std::filesystem::absolute(a.dir).lexically_normal().c_str(), summary.frames,
              summary.scenes, summary.scenes == 1 ? "" : "s", summary.seconds);
  return 0;
}

int RunInspect(const Args& a) {
  cadsynth::ImportOptions options;
  options.unit = a.unit;
  options.encoding = a.encoding;
  options.tessellation.linear_deflection_mm = a.deflection_mm;
  std::optional<cadsynth::ReaderProcess> reader;
  if (const std::filesystem::path self = SelfExecutable(); !self.empty())
    reader = cadsynth::ReaderProcess{self, cadsynth::RunLimits{}.read_timeout_s};
  const cadsynth::ReaderProcess* guard = reader ? &*reader : nullptr;
  std::cout << (a.json ? cadsynth::InspectJson(a.file, options, guard)
                       : cadsynth::InspectText(a.file, options, guard));
  return 0;
}

int RunVariants(const Args& a) {
  if (a.families) {
    std::cout << cadsynth::FamilyTable();
    return 0;
  }
  const cadsynth::RunSpec spec =
      !a.recipe.empty() ? cadsynth::LoadRecipe(a.recipe) : cadsynth::DefaultRunSpec();
  if (a.export_dir.empty()) {
    for (const cadsynth::VariantListing& v : cadsynth::ListVariants(spec))
      std::cout << v.id << "  " << v.params << "\n";
    return 0;
  }
  const auto written = cadsynth::ExportVariants(spec, a.export_dir, a.overwrite);
  for (const cadsynth::VariantListing& v : written)
    std::cout << v.step.string() << "  " << v.params << "\n";
  std::cout << "wrote " << written.size() << " STEP files\n";
  return 0;
}

int RunEval(const Args& a) {
  const cadsynth::EvalReport report = cadsynth::Evaluate(a.dir, a.results, a.sensor);
  std::cout << cadsynth::EvalTable(report);
  if (!a.json_file.empty()) cadsynth::WriteEvalJson(a.json_file, report);
  return 0;
}

int ParseCount(const std::string& option, const std::string& text, int lo, int hi) {
  char* end = nullptr;
  const long value = std::strtol(text.c_str(), &end, 10);
  if (end == text.c_str() || *end != '\0' || value < lo || value > hi) {
    throw UsageError{option + " takes a whole number from " + std::to_string(lo) + " to " +
                     std::to_string(hi) + ", got '" + text + "'"};
  }
  return static_cast<int>(value);
}

int RunPreview(const Args& a) {
  cadsynth::PreviewOptions options;
  options.count = a.count;
  options.panel_width = a.width;
  options.grasps = a.grasps;
  options.versus = a.versus;
  options.sensor = a.sensor;
  std::stringstream list(a.frames);
  for (std::string item; std::getline(list, item, ',');) {
    const size_t slash = item.find('/');
    if (slash == std::string::npos)
      throw UsageError{"--frames takes scene/image pairs like 0/12, got '" + item + "'"};
    options.frames.push_back({ParseCount("--frames scene", item.substr(0, slash), 0, 999999),
                              ParseCount("--frames image", item.substr(slash + 1), 0, 999999)});
  }
  const std::filesystem::path out = !a.output.empty()
                                        ? std::filesystem::path(a.output)
                                        : std::filesystem::path(a.dir) / "preview.png";
  std::vector<std::pair<int, int>> shown;
  const std::string png = cadsynth::RenderPreview(a.dir, options, &shown);
  cadsynth::WriteFileAtomic(out, png);
  std::cout << "wrote " << out.string() << " (" << shown.size() << " frames)\n";
  return 0;
}

// Verifies DATASET (a.dir) and writes the certificate (--certificate, default
// DATASET/verify.json), where `report` finds it too.
cadsynth::VerifyReport VerifyAndCertify(const Args& a, std::filesystem::path* certificate) {
  cadsynth::VerifyOptions options;
  options.pixels_per_image = a.pixels;
  *certificate = !a.certificate.empty() ? std::filesystem::path(a.certificate)
                                        : std::filesystem::path(a.dir) / cadsynth::kCertificateFile;
  // A certificate that cannot be written is known before the dataset is read.
  std::error_code ec;
  const std::filesystem::path folder = std::filesystem::absolute(*certificate).parent_path();
  if (std::filesystem::is_directory(a.dir, ec) && !std::filesystem::is_directory(folder, ec))
    throw cadsynth::Error(certificate->string() + ": cannot write: no folder " + folder.string());
  const cadsynth::VerifyReport report = cadsynth::VerifyDataset(a.dir, options);
  cadsynth::WriteFileAtomic(*certificate, report.CertificateJson());
  return report;
}

int RunVerify(const Args& a) {
  std::filesystem::path certificate;
  const cadsynth::VerifyReport report = VerifyAndCertify(a, &certificate);
  if (!report.passed()) {
    const size_t shown = std::min<size_t>(report.problems.size(), 20);
    for (size_t k = 0; k < shown; ++k)
      std::cout << report.problems[k].file << ": " << report.problems[k].reason << "\n";
    if (report.problem_count > shown)
      std::cout << "... and " << report.problem_count - shown << " more (" << certificate.string()
                << " lists " << report.problems.size() << ")\n";
  }
  for (const std::string& note : report.notes) std::cout << "note: " << note << "\n";
  std::cout << report.Verdict() << "\n";
  return report.passed() ? 0 : 1;
}

int RunReport(const Args& a) {
  if (a.verify_first) {
    std::filesystem::path certificate;
    std::cout << VerifyAndCertify(a, &certificate).Verdict() << "\n";
  }
  const std::filesystem::path out = !a.output.empty()
                                        ? std::filesystem::path(a.output)
                                        : std::filesystem::path(a.dir) / cadsynth::kReportFile;
  if (!a.data_file.empty()) {
    cadsynth::WriteFileAtomic(a.data_file, cadsynth::ReportData(a.dir));
    std::cout << "wrote " << a.data_file << "\n";
    return 0;
  }
  cadsynth::WriteReport(a.dir, out);
  std::error_code ec;
  std::cout << "wrote " << out.string() << " (" << std::filesystem::file_size(out, ec) / 1024
            << " KiB)\n";
  return 0;
}

int RunSensorTest(const Args& a) {
  if (a.list) {
    for (const cadsynth::SensorPreset& p : cadsynth::SensorPresets()) {
      std::cout << p.name << ": " << p.what << " (camera preset " << p.camera << ", "
                << cadsynth::Count(p.figures.size(), "published figure", "published figures")
                << ")\n";
    }
    return 0;
  }
  if (a.file.empty()) throw UsageError{"give a sensor preset (--list shows them) or a recipe"};
  cadsynth::PlaneTestOptions options;
  const std::filesystem::path path(a.file);
  if (path.extension() == ".yaml" || path.extension() == ".yml") {
    const cadsynth::RunSpec spec = cadsynth::LoadRecipe(a.file);
    options.name = path.filename().string();
    options.intrinsics = spec.intrinsics;
    options.sensor = spec.sensor;
    if (!a.sensor.empty()) {
      const auto it =
          std::find_if(spec.rig.begin(), spec.rig.end(),
                       [&](const cadsynth::RigSensor& r) { return r.name == a.sensor; });
      if (it == spec.rig.end()) {
        throw cadsynth::Error(a.file + ": no camera called '" + a.sensor + "' in its cameras:");
      }
      options.intrinsics = it->intrinsics;
      options.sensor = it->sensor;
      options.name += " " + a.sensor;
    }
    if (options.sensor.depth.kind == cadsynth::DepthModel::Kind::kIdeal) {
      throw cadsynth::Error(a.file + ": camera.depth is ideal (exact depth): nothing to test");
    }
  } else {
    const cadsynth::SensorPreset* preset = cadsynth::FindSensorPreset(a.file);
    if (preset == nullptr) {
      std::string names;
      for (const cadsynth::SensorPreset& p : cadsynth::SensorPresets()) {
        names += (names.empty() ? "" : ", ") + p.name;
      }
      throw UsageError{"no sensor preset called '" + a.file + "' (presets: " + names +
                       "; or give a recipe, FILE.yaml)"};
    }
    options = cadsynth::PlaneTestFor(*preset);
  }
  if (!a.distances_mm.empty()) options.distances_mm = a.distances_mm;
  if (!a.tilts_deg.empty()) {
    options.tilts_rad.clear();
    for (const double t : a.tilts_deg) options.tilts_rad.push_back(t * M_PI / 180.0);
  }
  if (a.albedo >= 0.0 || !a.material.empty())
    options.figures.clear();  // measured on another target
  if (a.albedo >= 0.0) options.albedo = a.albedo;
  options.material = a.material;
  options.frames = a.test_frames;
  options.roi = a.roi;
  options.step_mm = a.step_mm;
  const cadsynth::PlaneTestResult result = cadsynth::RunPlaneTest(options);
  if (a.json) {
    std::cout << cadsynth::PlaneTestJson(result);
  } else {
    std::cout << cadsynth::PlaneTestTable(result);
  }
  if (!a.output.empty()) {
    const std::filesystem::path dir(a.output);
    std::filesystem::create_directories(dir);
    cadsynth::WriteFileAtomic(dir / "sensor_test.json", cadsynth::PlaneTestJson(result));
    cadsynth::WriteFileAtomic(dir / "sensor_test.svg", cadsynth::PlaneTestSvg(result));
    if (!a.json)
      std::cout << "wrote " << (dir / "sensor_test.json").string() << " and sensor_test.svg\n";
  }
  if (a.check && !result.AllMet()) {
    std::cerr << "error: " << options.name << " misses published figures (NOT MET above)\n";
    return 1;
  }
  return 0;
}

// The subcommands and their options, each described once: CLI11 parses them and writes each
// subcommand's --help from the descriptions.
struct Command {
  CLI::App* app;
  int (*run)(const Args&);
};

std::vector<Command> DefineCommands(CLI::App& app, Args& a) {
  std::vector<Command> commands;
  const auto add = [&](const char* name, const char* what, int (*run)(const Args&)) {
    CLI::App* sub = app.add_subcommand(name, what);
    sub->formatter(app.get_formatter());
    sub->set_help_flag("-h,--help", "this help");
    commands.push_back({sub, run});
    return sub;
  };

  CLI::App* gen = add(
      "generate",
      "Renders every view of the recipe's camera sweep and writes a BOP dataset to DIR. Without "
      "a recipe it runs the built-in default job (no input files needed). A killed or failed run "
      "continues where it stopped when started again (same command).",
      RunGenerate);
  gen->add_option("RECIPE", a.recipe, "recipe (YAML); none: the built-in default job");
  gen->add_option("-o,--output", a.output,
                  "output folder (default: the recipe's output.dir, else ./cadsynth_dataset)")
      ->type_name("DIR");
  gen->add_flag("--overwrite", a.overwrite,
                "replace DIR if it exists (the old one stays until the new one is complete)");
  gen->add_flag("--strict", a.strict,
                "warnings that describe a broken dataset are errors: parts kept outside their "
                "container, parts still moving after settle_time, a camera inside or touching "
                "the scene");
  gen->add_option(
         "--shard", a.shard,
         "render only shard I of N (0 <= I < N) into DIR, beside the other shards; join them with "
         "'cadsynth merge DIR' once all have finished (tools/slurm/ runs both). 'auto': the "
         "array task's shard, from SLURM_ARRAY_TASK_ID (of the array's range), "
         "JOB_COMPLETION_INDEX (a Kubernetes Indexed Job; needs --shards), "
         "AWS_BATCH_JOB_ARRAY_INDEX/_SIZE or BATCH_TASK_INDEX/_COUNT (Google Cloud Batch)")
      ->type_name("I/N|auto");
  gen->add_option("--shards", a.shards,
                  "with --shard auto: the shard count (a Kubernetes Job's completions); one a "
                  "scheduler sets must equal it; with Slurm, the task ID is then the shard index")
      ->check(CLI::Range(1, cadsynth::ShardSpec::kMaxCount))
      ->type_name("N");
  gen->add_option("-j,--threads", a.threads,
                  "worker threads (default: all cores); results do not depend on it")
      ->check(CLI::Range(1, 1024))
      ->type_name("N");
  gen->add_option(
         "--progress", a.progress,
         "auto (a bar on a terminal, lines in a log), bar, lines, or json: one JSON line every 5 s "
         "(done, total, seconds, frames_per_s, s_per_frame, eta_s) for cluster logs")
      ->check(CLI::IsMember({"auto", "bar", "lines", "json"}))
      ->type_name("MODE");
  gen->add_flag(
      "-q,--quiet", a.quiet,
      "no progress or info lines, only warnings and errors (--progress=json still prints)");
  CLI::Option* cache =
      gen->add_option("--cache", a.cache,
                      "the part cache (imported parts, hulls, repeated shapes, symmetries, grasps; "
                      "shared by runs and shards; default $CADSYNTH_CACHE, else "
                      "$XDG_CACHE_HOME/cadsynth or ~/.cache/cadsynth)")
          ->type_name("DIR");
  gen->add_flag("--no-cache", a.no_cache,
                "read and analyse every part afresh (the output is the same bytes either way)")
      ->excludes(cache);
  gen->add_flag("--help-recipe", a.help_recipe,
                "print every recipe key, section by section, with its kind, default and meaning");
  gen->add_flag("--recipe-schema", a.recipe_schema,
                "print the recipe's JSON Schema (for editors and checkers; docs/recipes.md)");

  CLI::App* merge = add(
      "merge",
      "Joins the shards in DIR (written by generate --shard) into one dataset, byte for byte the "
      "one a single process writes; refuses, naming them, while shards are unfinished, and "
      "checks every frame's files against the manifest (size and CRC-32).",
      RunMerge);
  merge->add_option("DIR", a.dir, "the folder the shards wrote to")->required();

  CLI::App* inspect =
      add("inspect",
          "Reads a STEP, IGES, BREP or mesh file (.stl .obj .ply .dae .gltf .glb .3mf .off) and "
          "prints what cadsynth sees: format, declared unit, parts with instance counts, size in "
          "mm, triangles, colour, volume and whether the mesh is closed, and every instance.",
          RunInspect);
  inspect->add_option("FILE", a.file, "the CAD or mesh file")->required();
  inspect->add_flag("--json", a.json, "machine-readable output");
  inspect
      ->add_option("--unit", a.unit,
                   "the unit the file's numbers are really in (overrides the file; meshes: mm)")
      ->type_name("UNIT");
  inspect
      ->add_option("--encoding", a.encoding,
                   "STEP names written as raw bytes of a code page: cp1251, cp1252, sjis, ...")
      ->type_name("CODEPAGE");
  inspect->add_option("--deflection", a.deflection_mm, "tessellation tolerance in mm")
      ->check(CLI::PositiveNumber)
      ->type_name("MM")
      ->capture_default_str();

  CLI::App* variants =
      add("variants",
          "Lists every variant of the recipe's part families (id and parameters, as in "
          "variants.json); with --export-step writes each as DIR/<id>.step (exact B-rep, mm).",
          RunVariants);
  variants->add_option("RECIPE", a.recipe, "recipe (YAML); none: the built-in default job");
  variants->add_option("--export-step", a.export_dir, "write each variant as DIR/<id>.step")
      ->type_name("DIR");
  variants->add_flag("--overwrite", a.overwrite, "replace existing STEP files");
  variants->add_flag("--families", a.families,
                     "list every part family with its parameters and defaults (Markdown) instead");

  CLI::App* eval =
      add("eval",
          "Scores pose estimates in the BOP results format (scene_id,im_id,obj_id,score,R,t,time) "
          "against DATASET's test split: ADD, ADD-S (for symmetric parts), the share within 10% of "
          "the diameter and the AUC of accuracy up to 0.1 m, per object and overall.",
          RunEval);
  eval->add_option("DATASET", a.dir, "a dataset cadsynth wrote")->required();
  eval->add_option("RESULTS", a.results, "the estimates, BOP's CSV format")->required();
  eval->add_option("--json", a.json_file, "also write the scores as JSON to FILE")
      ->type_name("FILE");
  eval->add_option("--sensor", a.sensor,
                   "a multi-sensor dataset's sensor the estimates are for (scene_gt_NAME.json)")
      ->type_name("NAME");

  CLI::App* preview =
      add("preview",
          "Writes a contact sheet PNG: per frame the colour image with every object's projected "
          "3D box and axes (x red, y green, z blue), the coloured depth and the visible masks.",
          RunPreview);
  preview->add_option("DATASET", a.dir, "a dataset cadsynth wrote")->required();
  preview->add_option("-o,--output", a.output, "output PNG (default: DATASET/preview.png)")
      ->type_name("FILE");
  auto* count = preview->add_option("--count", a.count, "frames spread evenly over the dataset")
                    ->check(CLI::Range(1, 1000))
                    ->type_name("N")
                    ->capture_default_str();
  preview->add_option("--frames", a.frames, "exactly these frames, as scene/image pairs: 0/0,2/17")
      ->type_name("LIST")
      ->excludes(count);
  preview
      ->add_option("--versus", a.versus,
                   "another dataset of the same views (e.g. render.mode: pbr): show the two "
                   "colour images side by side")
      ->type_name("DATASET2");
  preview->add_option("--sensor", a.sensor, "a multi-sensor dataset's sensor (rgb_NAME/, ...)")
      ->type_name("NAME");
  preview->add_option("--width", a.width, "width of each of the three panels in pixels")
      ->check(CLI::Range(32, 4096))
      ->type_name("PX")
      ->capture_default_str();
  preview
      ->add_option("--grasps", a.grasps,
                   "with grasp labels, each frame's N best grasps whose way in is free (0: none)")
      ->check(CLI::Range(0, 1000))
      ->type_name("N")
      ->capture_default_str();

  CLI::App* verify = add(
      "verify",
      "Checks a dataset on its own: every file against the manifest (size, CRC-32), every "
      "scene_gt_info entry and COCO mask against the mask PNGs, models_info against the models, "
      "and a sample of pixels re-cast through the models at the written poses against the depth "
      "and masks. Prints a one-line verdict, writes a JSON certificate; exit 1 on any problem.",
      RunVerify);
  verify->add_option("DATASET", a.dir, "a dataset cadsynth wrote")->required();
  verify
      ->add_option("--certificate", a.certificate,
                   "where to write the JSON certificate (default: DATASET/verify.json)")
      ->type_name("FILE");
  verify->add_option("--pixels", a.pixels, "pixels re-cast per image and sensor (0: none)")
      ->check(CLI::Range(0, 100000))
      ->type_name("N")
      ->capture_default_str();

  CLI::App* report = add(
      "report",
      "Writes one self-contained HTML page about a dataset: the run, the verifier's verdict, per "
      "object its viewpoint coverage (folded by its symmetries), in-plane rotation, distance and "
      "visibility, per image occlusion and depth range, the randomised draws, grasps, pick "
      "sequences and a gallery of the extreme frames. Plots need Python with matplotlib.",
      RunReport);
  report->add_option("DATASET", a.dir, "a dataset cadsynth wrote")->required();
  report->add_option("-o,--output", a.output, "output HTML (default: DATASET/report.html)")
      ->type_name("FILE");
  report->add_flag("--verify", a.verify_first,
                   "run the verifier first (writes DATASET/verify.json; the report shows it)");
  report
      ->add_option("--data", a.data_file,
                   "write the report's data (JSON) to FILE instead of the page")
      ->type_name("FILE");

  CLI::App* sensor = add(
      "sensor-test",
      "Measures a depth sensor the way its makers do: a flat target at a series of distances "
      "(and tilts), rendered several times through the sensor's depth model, and reports temporal "
      "noise, plane-fit RMS, bias, fill rate and the holes and wrong pixels at a step, with the "
      "sensor preset's published figures beside them. SENSOR is a sensor preset (--list) or a "
      "recipe, whose camera is tested.",
      RunSensorTest);
  sensor->add_option("SENSOR", a.file, "a sensor preset, or a recipe (FILE.yaml)");
  sensor->add_flag("--list", a.list, "list the sensor presets");
  sensor->add_option("--camera", a.sensor, "a recipe's rig: the camera called NAME")
      ->type_name("NAME");
  sensor
      ->add_option("--distances", a.distances_mm,
                   "distances to the target along the optical axis, mm (default: the preset's "
                   "figures' distances, else 500,1000,2000,3000)")
      ->delimiter(',')
      ->type_name("MM,...");
  sensor
      ->add_option("--tilts", a.tilts_deg,
                   "tilts of the target, degrees; positive turns it towards the projector "
                   "(default 0)")
      ->delimiter(',')
      ->type_name("DEG,...");
  sensor
      ->add_option("--albedo", a.albedo,
                   "the target's diffuse reflectance (default: the preset's, 0.8); another "
                   "target than the figures' drops them")
      ->check(CLI::Range(0.0, 1.0))
      ->type_name("A");
  sensor
      ->add_option("--material", a.material,
                   "a material preset for the target instead (path-traced return: polished "
                   "metals lose depth)")
      ->type_name("NAME");
  sensor->add_option("--frames", a.test_frames, "repeated frames for the temporal noise")
      ->check(CLI::Range(2, 1000))
      ->capture_default_str();
  sensor->add_option("--roi", a.roi, "central share of the image's width and height measured")
      ->check(CLI::Range(0.01, 1.0))
      ->capture_default_str();
  sensor->add_option("--step", a.step_mm, "height of the edge test's step, mm (0: none)")
      ->check(CLI::Range(0.0, 1000.0))
      ->capture_default_str();
  sensor->add_option("-o,--output", a.output, "also write DIR/sensor_test.json and .svg (a plot)")
      ->type_name("DIR");
  sensor->add_flag("--json", a.json, "print JSON instead of the table");
  sensor->add_flag("--check", a.check, "exit 1 when a published figure is not met");
  return commands;
}

// `cadsynth --help`: a usage line and the description of each command, from the same CLI11
// descriptions as each command's own --help (docs/cli.md is generated from both).
std::string TopLevelHelp(const CLI::App& app, const std::vector<Command>& commands) {
  std::ostringstream out;
  out << app.get_description() << "\n\nusage:\n";
  for (const Command& c : commands) {
    out << "  cadsynth " << c.app->get_name();
    bool options = false;
    for (const CLI::Option* o : c.app->get_options()) {
      if (o->get_positional()) {
        const std::string name = o->get_name();
        out << " " << (o->get_required() ? name : "[" + name + "]");
      } else if (o != c.app->get_help_ptr()) {
        options = true;
      }
    }
    out << (options ? " [OPTIONS]" : "") << "\n";
  }
  out << "  cadsynth --help | --version\n"
         "  cadsynth COMMAND --help       every option of one command\n";
  for (const Command& c : commands) {
    // The description wrapped at 100 columns beside the command's name.
    std::istringstream words(c.app->get_description());
    std::string word, line = c.app->get_name();
    line.resize(10, ' ');
    const size_t start = line.size();
    out << "\n";
    while (words >> word) {
      if (line.size() > start && line.size() + 1 + word.size() > 100) {
        out << line << "\n";
        line.assign(start, ' ');
      }
      line += (line.size() > start ? " " : "") + word;
    }
    out << line << "\n";
  }
  return out.str();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"cadsynth: CAD in, labelled RGB-D training data out.", "cadsynth"};
  app.set_help_flag();  // the top-level help lists the commands: TopLevelHelp
  app.set_version_flag("--version", std::string("cadsynth ") + CADSYNTH_VERSION);
  app.require_subcommand(0, 1);
  app.get_formatter()->column_width(24);
  Args args;
  cadsynth::SilenceOpenCvWarnings();
  const std::vector<Command> commands = DefineCommands(app, args);
  const std::string first = argc > 1 ? argv[1] : "";
  // The child of a guarded read (tools/pipeline/guarded_import.h): not a user command.
  if (first == "__read-part") return cadsynth::ReadPartMain({argv + 2, argv + argc});
  if (argc < 2 || first == "--help" || first == "-h" || first == "help") {
    std::cout << TopLevelHelp(app, commands);
    return argc < 2 ? 2 : 0;
  }
  const auto usage_error = [&](const std::string& what, const std::string& command) {
    std::cerr << "error: " << what << "\n(run 'cadsynth " << (command.empty() ? "" : command + " ")
              << "--help' for usage)\n";
    return 2;
  };
  const bool known = first == "--version" ||
                     std::any_of(commands.begin(), commands.end(),
                                 [&](const Command& c) { return c.app->get_name() == first; });
  if (!known)
    return usage_error((first[0] == '-' ? "unknown option '" : "unknown command '") + first + "'",
                       "");
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);  // --help of a subcommand, --version
  } catch (const CLI::ParseError& e) {
    // CLI11's words for an unexpected argument; ours names it.
    std::string what = e.what();
    const std::string extra = "The following argument was not expected: ";
    if (what.rfind(extra, 0) == 0 && what.size() > extra.size() && what[extra.size()] == '-') {
      what = "unknown option '" + what.substr(extra.size()) + "'";
    }
    return usage_error(what, first);
  }
  try {
    for (const Command& command : commands) {
      if (command.app->parsed()) return command.run(args);
    }
    return usage_error("no command given", "");
  } catch (const UsageError& e) {
    return usage_error(e.what, first);
  } catch (const cadsynth::Error& e) {
    std::cerr << "error: " << Shortened(e.what()) << "\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "error: out of memory: the input asks for more than this machine has (a huge "
                 "mesh, grid or image size?)\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "error: internal: " << Shortened(e.what()) << "\n";
    return 1;
  }
}
