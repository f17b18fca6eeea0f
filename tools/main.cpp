// The cadsynth command line. Owns threads (one tbb::global_control), logging and exit codes.
#include <unistd.h>

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

#include "cad/error.h"
#include "recipes/recipe.h"
#include "dataset/file_io.h"
#include "dataset/preview.h"
#include "tools/eval.h"
#include "tools/export.h"
#include "tools/generate.h"
#include "tools/inspect.h"
#include "tools/progress.h"
#include "tools/shards.h"

namespace {

constexpr const char* kUsage = R"(cadsynth: CAD in, labelled RGB-D training data out.

usage:
  cadsynth generate [RECIPE.yaml] [-o DIR] [--overwrite] [--shard I/N] [--threads N] [--progress=MODE] [--quiet]
  cadsynth merge DIR
  cadsynth inspect FILE [--json] [--unit UNIT] [--encoding CODEPAGE] [--deflection MM]
  cadsynth variants RECIPE.yaml [--export-step DIR] [--overwrite]
  cadsynth eval DATASET RESULTS.csv [--json FILE]
  cadsynth preview DATASET [-o FILE.png] [--count N | --frames S/I,...] [--width PX]
  cadsynth --help | --version

generate   Renders every view of the recipe's camera sweep and writes a BOP dataset to DIR.
           Without a recipe it runs the built-in default job (no input files needed).
  -o DIR       output folder (default: the recipe's output.dir, else ./cadsynth_dataset)
  --overwrite  replace DIR if it exists (the old one stays until the new one is complete)
  --shard I/N  render only shard I of N (0 <= I < N) into DIR, beside the other shards; join
               them with 'cadsynth merge DIR' once all have finished (tools/slurm/ runs both)
  --threads N  worker threads (default: all cores); results do not depend on it
  --progress=MODE  auto (a bar on a terminal, lines in a log), bar, lines, or json: one JSON
               line every 5 s (done, total, seconds, frames_per_s, eta_s) for cluster logs
  --quiet      no progress or info lines, only warnings and errors (--progress=json still prints)

           A killed or failed run continues where it stopped when started again (same command).

merge      Joins the shards in DIR (written by generate --shard) into one dataset, byte for byte
           the one a single process writes; refuses, naming them, while shards are unfinished,
           and checks every frame's files against the manifest (size and CRC-32).

inspect    Reads a STEP, IGES, BREP or mesh file (.stl .obj .ply .dae .gltf .glb .3mf .off) and
           prints what cadsynth sees: format, declared unit, parts with instance counts, size in
           mm, triangles, colour, volume and whether the mesh is closed, and every instance.
  --json           machine-readable output
  --unit UNIT      the unit the file's numbers are really in (overrides the file; meshes: mm)
  --encoding CP    STEP names written as raw bytes of a code page: cp1251, cp1252, sjis, ...
  --deflection MM  tessellation tolerance (default 0.1 mm)

variants   Lists every variant of the recipe's part families (id and parameters, as in
           variants.json); with --export-step writes each as DIR/<id>.step (exact B-rep, mm).

eval       Scores pose estimates in the BOP results format (scene_id,im_id,obj_id,score,R,t,time)
           against DATASET's test split: ADD, ADD-S (for symmetric parts), the share within 10%
           of the diameter and the AUC of accuracy up to 0.1 m, per object and overall.
  --json FILE  also write the scores as JSON

preview    Writes a contact sheet PNG: per frame the colour image with every object's projected
           3D box and axes (x red, y green, z blue), the coloured depth and the visible masks.
  -o FILE        output (default: DATASET/preview.png)
  --count N      frames spread evenly over the dataset (default 4)
  --frames LIST  exactly these frames, as scene/image pairs: 0/0,2/17
  --width PX     width of each of the three panels (default 320)
)";

struct UsageError {
  std::string what;
};

int ParseThreads(const std::string& text) {
  char* end = nullptr;
  const long value = std::strtol(text.c_str(), &end, 10);
  if (end == text.c_str() || *end != '\0' || value < 1 || value > 1024) {
    throw UsageError{"--threads takes a whole number from 1 to 1024, got '" + text + "'"};
  }
  return static_cast<int>(value);
}

int RunGenerate(const std::vector<std::string>& args) {
  std::optional<std::string> recipe, output;
  bool overwrite = false, quiet = false;
  int threads = 0;
  std::string progress = "auto";
  std::optional<cadsynth::ShardSpec> shard;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= args.size()) throw UsageError{a + " needs a value"};
      return args[++i];
    };
    if (a == "-o" || a == "--output") {
      output = value();
    } else if (a == "--overwrite") {
      overwrite = true;
    } else if (a == "--shard" || a.rfind("--shard=", 0) == 0) {
      const std::string text = a == "--shard" ? value() : a.substr(8);
      try {
        shard = cadsynth::ParseShard(text);
      } catch (const cadsynth::Error& e) {
        throw UsageError{e.what()};
      }
    } else if (a == "--quiet" || a == "-q") {
      quiet = true;
    } else if (a == "--threads" || a == "-j") {
      threads = ParseThreads(value());
    } else if (a == "--progress" || a.rfind("--progress=", 0) == 0) {
      progress = a == "--progress" ? value() : a.substr(11);
      if (progress != "auto" && progress != "bar" && progress != "lines" && progress != "json") {
        throw UsageError{"--progress takes auto, bar, lines or json, got '" + progress + "'"};
      }
    } else if (!a.empty() && a[0] == '-') {
      throw UsageError{"unknown option '" + a + "'"};
    } else if (recipe) {
      throw UsageError{"one recipe at a time (got '" + *recipe + "' and '" + a + "')"};
    } else {
      recipe = a;
    }
  }

  std::unique_ptr<tbb::global_control> thread_limit;
  if (threads > 0) {
    thread_limit = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
  }

  const cadsynth::RunSpec spec = recipe ? cadsynth::LoadRecipe(*recipe) : cadsynth::DefaultRunSpec();
  cadsynth::GenerateOptions options;
  options.output = output ? std::filesystem::path(*output)
                          : (!spec.output.empty() ? spec.output : "cadsynth_dataset");
  options.overwrite = overwrite;
  options.shard = shard;
  if (!quiet) {
    options.info = [](const std::string& line) { std::cout << line << "\n" << std::flush; };
  }
  if (!quiet || progress == "json") {
    using Mode = cadsynth::ProgressReporter::Mode;
    const Mode mode = progress == "json"  ? Mode::kJson
                      : progress == "bar" ? Mode::kBar
                      : progress == "lines" ? Mode::kLines
                      : ::isatty(STDERR_FILENO) != 0 ? Mode::kBar
                                                     : Mode::kLines;
    auto reporter = std::make_shared<cadsynth::ProgressReporter>(mode, stderr);
    if (shard) reporter->SetShard(shard->Name());
    options.progress = [reporter](size_t done, size_t total) { reporter->Update(done, total); };
  }
  const cadsynth::GenerateSummary summary = cadsynth::Generate(spec, options);
  if (summary.skipped_empty + summary.skipped_sparse > 0) {
    std::printf("skipped %zu views: %zu showed no object, %zu fewer than %d object pixels\n",
                summary.skipped_empty + summary.skipped_sparse, summary.skipped_empty, summary.skipped_sparse,
                spec.min_visible_pixels);
  }
  const size_t rendered = summary.frames - summary.resumed;
  std::printf("wrote %zu frames (%zu scene%s) of %zu objects (%zu instances)%s to %s in %.1f s (%.1f frames/s)\n",
              summary.frames, summary.scenes, summary.scenes == 1 ? "" : "s", summary.objects, summary.instances,
              shard ? (" as shard " + shard->Name()).c_str() : "",
              std::filesystem::absolute(options.output).lexically_normal().c_str(), summary.seconds,
              summary.seconds > 0 ? rendered / summary.seconds : 0.0);
  return 0;
}

int RunMerge(const std::vector<std::string>& args) {
  std::optional<std::string> dir;
  for (const std::string& a : args) {
    if (!a.empty() && a[0] == '-') throw UsageError{"unknown option '" + a + "'"};
    if (dir) throw UsageError{"one folder at a time"};
    dir = a;
  }
  if (!dir) throw UsageError{"merge needs the DIR the shards wrote to"};
  const cadsynth::MergeSummary summary = cadsynth::Merge(*dir);
  std::printf("merged %d shard%s into %s: %zu frames in %zu scene%s, %.1f s\n", summary.shards,
              summary.shards == 1 ? "" : "s", std::filesystem::absolute(*dir).lexically_normal().c_str(),
              summary.frames, summary.scenes, summary.scenes == 1 ? "" : "s", summary.seconds);
  return 0;
}

int RunInspect(const std::vector<std::string>& args) {
  std::optional<std::string> file;
  bool json = false;
  cadsynth::ImportOptions options;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= args.size()) throw UsageError{a + " needs a value"};
      return args[++i];
    };
    if (a == "--json") {
      json = true;
    } else if (a == "--unit") {
      options.unit = value();
    } else if (a == "--encoding") {
      options.encoding = value();
    } else if (a == "--deflection") {
      const std::string text = value();
      char* end = nullptr;
      options.tessellation.linear_deflection_mm = std::strtod(text.c_str(), &end);
      if (end == text.c_str() || *end != '\0') throw UsageError{"--deflection takes a number of mm, got '" + text + "'"};
    } else if (!a.empty() && a[0] == '-') {
      throw UsageError{"unknown option '" + a + "'"};
    } else if (file) {
      throw UsageError{"one file at a time"};
    } else {
      file = a;
    }
  }
  if (!file) throw UsageError{"inspect needs a FILE"};
  std::cout << (json ? cadsynth::InspectJson(*file, options) : cadsynth::InspectText(*file, options));
  return 0;
}

int RunVariants(const std::vector<std::string>& args) {
  std::optional<std::string> recipe, dir;
  bool overwrite = false;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--export-step") {
      if (i + 1 >= args.size()) throw UsageError{"--export-step needs a folder"};
      dir = args[++i];
    } else if (a == "--overwrite") {
      overwrite = true;
    } else if (!a.empty() && a[0] == '-') {
      throw UsageError{"unknown option '" + a + "'"};
    } else if (recipe) {
      throw UsageError{"one recipe at a time"};
    } else {
      recipe = a;
    }
  }
  const cadsynth::RunSpec spec = recipe ? cadsynth::LoadRecipe(*recipe) : cadsynth::DefaultRunSpec();
  if (!dir) {
    for (const cadsynth::VariantListing& v : cadsynth::ListVariants(spec)) std::cout << v.id << "  " << v.params << "\n";
    return 0;
  }
  const auto written = cadsynth::ExportVariants(spec, *dir, overwrite);
  for (const cadsynth::VariantListing& v : written) std::cout << v.step.string() << "  " << v.params << "\n";
  std::cout << "wrote " << written.size() << " STEP files\n";
  return 0;
}

int RunEval(const std::vector<std::string>& args) {
  std::vector<std::string> positional;
  std::optional<std::string> json;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--json") {
      if (i + 1 >= args.size()) throw UsageError{"--json needs a file"};
      json = args[++i];
    } else if (!a.empty() && a[0] == '-') {
      throw UsageError{"unknown option '" + a + "'"};
    } else {
      positional.push_back(a);
    }
  }
  if (positional.size() != 2) throw UsageError{"eval needs DATASET and RESULTS.csv"};
  const cadsynth::EvalReport report = cadsynth::Evaluate(positional[0], positional[1]);
  std::cout << cadsynth::EvalTable(report);
  if (json) cadsynth::WriteEvalJson(*json, report);
  return 0;
}

int ParseCount(const std::string& option, const std::string& text, int lo, int hi) {
  char* end = nullptr;
  const long value = std::strtol(text.c_str(), &end, 10);
  if (end == text.c_str() || *end != '\0' || value < lo || value > hi) {
    throw UsageError{option + " takes a whole number from " + std::to_string(lo) + " to " + std::to_string(hi) +
                     ", got '" + text + "'"};
  }
  return static_cast<int>(value);
}

int RunPreview(const std::vector<std::string>& args) {
  std::optional<std::string> dataset, output;
  cadsynth::PreviewOptions options;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    const bool takes_value = a == "-o" || a == "--count" || a == "--frames" || a == "--width";
    if (takes_value && i + 1 >= args.size()) throw UsageError{a + " needs a value"};
    if (a == "-o") {
      output = args[++i];
    } else if (a == "--count") {
      options.count = ParseCount(a, args[++i], 1, 1000);
    } else if (a == "--width") {
      options.panel_width = ParseCount(a, args[++i], 32, 4096);
    } else if (a == "--frames") {
      std::stringstream list(args[++i]);
      for (std::string item; std::getline(list, item, ',');) {
        const size_t slash = item.find('/');
        if (slash == std::string::npos) throw UsageError{"--frames takes scene/image pairs like 0/12, got '" + item + "'"};
        options.frames.push_back({ParseCount("--frames scene", item.substr(0, slash), 0, 999999),
                                  ParseCount("--frames image", item.substr(slash + 1), 0, 999999)});
      }
    } else if (!a.empty() && a[0] == '-') {
      throw UsageError{"unknown option '" + a + "'"};
    } else if (dataset) {
      throw UsageError{"one dataset at a time"};
    } else {
      dataset = a;
    }
  }
  if (!dataset) throw UsageError{"preview needs a DATASET folder"};
  const std::filesystem::path out = output ? std::filesystem::path(*output) : std::filesystem::path(*dataset) / "preview.png";
  std::vector<std::pair<int, int>> shown;
  const std::string png = cadsynth::RenderPreview(*dataset, options, &shown);
  cadsynth::WriteFileAtomic(out, png);
  std::cout << "wrote " << out.string() << " (" << shown.size() << " frames)\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  try {
    if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
      std::cout << kUsage;
      return args.empty() ? 2 : 0;
    }
    if (args[0] == "--version") {
      std::cout << "cadsynth " << CADSYNTH_VERSION << "\n";
      return 0;
    }
    if (args[0] == "generate") return RunGenerate({args.begin() + 1, args.end()});
    if (args[0] == "merge") return RunMerge({args.begin() + 1, args.end()});
    if (args[0] == "inspect") return RunInspect({args.begin() + 1, args.end()});
    if (args[0] == "variants") return RunVariants({args.begin() + 1, args.end()});
    if (args[0] == "eval") return RunEval({args.begin() + 1, args.end()});
    if (args[0] == "preview") return RunPreview({args.begin() + 1, args.end()});
    throw UsageError{"unknown command '" + args[0] + "'"};
  } catch (const UsageError& e) {
    std::cerr << "error: " << e.what << "\n(run 'cadsynth --help' for usage)\n";
    return 2;
  } catch (const cadsynth::Error& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "error: internal: " << e.what() << "\n";
    return 1;
  }
}
