// Piles at rest (issue 45): drops N copies of a part into the default tote for each seed, then
// checks the rest the way a user would, a new world started from the resting poses and simulated
// for one more second (ContinuePile): how far the most mobile point of any part moved. Prints one
// line per seed (wall time of the drop, simulated seconds, restless parts, the resimulation's
// drift) and the median and worst.
//
//   build/bench/cadsynth_bench_pile --family hex_bolt --param size=M16 --param length=60
//       --count 60 --seeds 1-24 [--jobs 2]
//
// Parts: a family (--family, --param name=value) or a CAD or mesh file (--file). The tote is
// PileOptions' default container made a tote (355 x 265 x 150 mm inside), as bin_picking.yaml.
// --jobs runs piles side by side (each on one thread). --drift-profile also prints each pile's
// resimulated drift after 0.02, 0.1, 0.25, 0.5 and 2 s (a creep grows linearly, a topple faster,
// a restart's jolt is there at once). --iterations sets PileOptions' solver_iterations,
// --no-confirm its confirm_seconds to 0 (the rest test alone), --rest-speed its rest_speed_mm_s.
// --concavity and --merge-volume set the collision shape's CollisionOptions (a concave part's
// pieces). --picks N then
// takes N parts out of each pile, the highest first, as a pick sequence does (SettleAfterPick):
// the wall time of each pick step and how many parts it freed, median and worst.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include "cad/core/error.h"
#include "cad/import.h"
#include "variants/families.h"
#include "variants/physics/collision.h"
#include "variants/physics/pile.h"

namespace {

using cadsynth::ParamValues;

struct Row {
  uint64_t seed = 0;
  double wall_s = 0, simulated_s = 0, drift_mm = 0, resim_wall_s = 0;
  size_t restless = 0, escaped = 0;
  std::vector<double> pick_wall_s;
  std::vector<int> pick_freed;
};

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n == 0 ? 0 : (n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]));
}

int Usage() {
  std::fprintf(stderr,
               "usage: cadsynth_bench_pile (--family NAME [--param KEY=VALUE]... | --file PATH)\n"
               "       [--count 60] [--seeds 1-24] [--jobs 1] [--no-resim] [--drift-profile]\n"
               "       [--iterations 50] [--no-confirm] [--rest-speed 2]\n"
               "       [--concavity 0.03] [--merge-volume 0.1] [--picks 0]\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) try {
  std::string family, file;
  ParamValues params;
  int count = 60, jobs = 1, first = 1, last = 24, picks = 0;
  bool resim = true, profile = false, confirm = true;
  int iterations = cadsynth::PileOptions{}.solver_iterations;
  double rest_speed = cadsynth::PileOptions{}.rest_speed_mm_s;
  cadsynth::CollisionOptions collision;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto next = [&]() -> std::string {
      if (i + 1 >= argc) std::exit(Usage());
      return argv[++i];
    };
    if (a == "--family") {
      family = next();
    } else if (a == "--file") {
      file = next();
    } else if (a == "--param") {
      const std::string kv = next();
      const size_t eq = kv.find('=');
      if (eq == std::string::npos) return Usage();
      const std::string key = kv.substr(0, eq), value = kv.substr(eq + 1);
      char* end = nullptr;
      const double number = std::strtod(value.c_str(), &end);
      if (end != value.c_str() && *end == '\0') {
        params[key] = number;
      } else {
        params[key] = value;
      }
    } else if (a == "--count") {
      count = std::stoi(next());
    } else if (a == "--jobs") {
      jobs = std::stoi(next());
    } else if (a == "--seeds") {
      const std::string s = next();
      const size_t dash = s.find('-');
      first = std::stoi(s.substr(0, dash));
      last = dash == std::string::npos ? first : std::stoi(s.substr(dash + 1));
    } else if (a == "--no-resim") {
      resim = false;
    } else if (a == "--drift-profile") {
      profile = true;
    } else if (a == "--iterations") {
      iterations = std::stoi(next());
    } else if (a == "--no-confirm") {
      confirm = false;
    } else if (a == "--rest-speed") {
      rest_speed = std::stod(next());
    } else if (a == "--concavity") {
      collision.concavity = std::stod(next());
    } else if (a == "--merge-volume") {
      collision.merge_volume = std::stod(next());
    } else if (a == "--picks") {
      picks = std::stoi(next());
    } else {
      return Usage();
    }
  }
  if (family.empty() == file.empty() || count < 1 || last < first || jobs < 1 || picks < 0 ||
      picks >= count)
    return Usage();
  try {
    cadsynth::Part part;
    if (!family.empty()) {
      const cadsynth::FamilyInfo* f = cadsynth::FindFamily(family);
      if (f == nullptr) throw cadsynth::Error("no family '" + family + "'");
      part = cadsynth::BuildVariant(*f, cadsynth::CompleteParams(*f, params),
                                    cadsynth::ImportOptions{})
                 .parts[0];
    } else {
      part = cadsynth::ImportCad(file, cadsynth::ImportOptions{}).parts[0];
    }
    const auto t0 = std::chrono::steady_clock::now();
    const std::vector<cadsynth::CollisionShape> shapes = {
        cadsynth::MakeCollisionShape(part, collision)};
    const double shape_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const std::vector<cadsynth::Part> parts = {part};
    std::printf("%s: %zu collision pieces, %.3f x its volume (%.2f s), %d copies, seeds %d-%d\n",
                part.name.c_str(), shapes[0].pieces.size(), shapes[0].volume_ratio, shape_s, count,
                first, last);
    std::vector<Row> rows(static_cast<size_t>(last - first + 1));
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, jobs);
    tbb::parallel_for(size_t{0}, rows.size(), [&](size_t k) {
      Row& row = rows[k];
      row.seed = static_cast<uint64_t>(first) + k;
      cadsynth::PileOptions o;
      o.bodies.assign(static_cast<size_t>(count), 0);
      o.container.kind = cadsynth::Container::Kind::kTote;
      o.seed = row.seed;
      o.solver_iterations = iterations;
      if (!confirm) o.confirm_seconds = 0.0;
      o.rest_speed_mm_s = rest_speed;
      auto start = std::chrono::steady_clock::now();
      const cadsynth::PileResult r = cadsynth::DropPile(parts, shapes, o);
      row.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      row.simulated_s = r.seconds;
      row.restless = r.restless.size();
      row.escaped = r.escaped.size();
      if (resim) {
        start = std::chrono::steady_clock::now();
        row.drift_mm = cadsynth::ContinuePile(parts, shapes, o, r.world_from_model, 1.0).drift_mm;
        if (profile) {
          std::string line = "seed " + std::to_string(row.seed) + " drift at";
          for (double t : {0.02, 0.1, 0.25, 0.5, 2.0}) {
            char buf[64];
            std::snprintf(buf, sizeof buf, " %.2fs %.2f", t,
                          cadsynth::ContinuePile(parts, shapes, o, r.world_from_model, t).drift_mm);
            line += buf;
          }
          std::printf("%s\n", line.c_str());
        }
        row.resim_wall_s =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      }
      // Picks, the highest part first.
      std::vector<Eigen::Isometry3d> poses = r.world_from_model;
      for (int k = 0; k < picks; ++k) {
        size_t top = 0;
        double top_z = -1e300;
        for (size_t i = 0; i < poses.size(); ++i) {
          for (const Eigen::Vector3f& v : part.mesh.positions) {
            const double z = (poses[i] * v.cast<double>()).z();
            if (z > top_z) top_z = z, top = i;
          }
        }
        std::vector<bool> freed;
        start = std::chrono::steady_clock::now();
        poses = cadsynth::SettleAfterPick(parts, shapes, o, poses, static_cast<int>(top), &freed)
                    .world_from_model;
        row.pick_wall_s.push_back(
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        row.pick_freed.push_back(static_cast<int>(std::count(freed.begin(), freed.end(), true)));
        o.bodies.pop_back();
      }
    });
    std::vector<double> wall, simulated, drift, pick_wall;
    int over = 0, restless = 0;
    for (const Row& row : rows) {
      std::printf("seed %3llu: %6.2f s wall, %5.2f s simulated, %zu restless, %zu escaped",
                  static_cast<unsigned long long>(row.seed), row.wall_s, row.simulated_s,
                  row.restless, row.escaped);
      if (resim)
        std::printf(", resimulated 1 s: %6.2f mm (%.2f s)", row.drift_mm, row.resim_wall_s);
      if (picks > 0) {
        std::printf(", %d picks: median %.3f s, worst %.3f s, freed median %.0f, most %d", picks,
                    Median(row.pick_wall_s),
                    *std::max_element(row.pick_wall_s.begin(), row.pick_wall_s.end()),
                    Median(std::vector<double>(row.pick_freed.begin(), row.pick_freed.end())),
                    *std::max_element(row.pick_freed.begin(), row.pick_freed.end()));
        pick_wall.insert(pick_wall.end(), row.pick_wall_s.begin(), row.pick_wall_s.end());
      }
      std::printf("\n");
      wall.push_back(row.wall_s);
      simulated.push_back(row.simulated_s);
      drift.push_back(row.drift_mm);
      over += resim && row.restless == 0 && row.drift_mm > 0.5;
      restless += row.restless > 0;
    }
    std::printf("wall: median %.2f s, worst %.2f s; simulated: median %.2f s, worst %.2f s\n",
                Median(wall), *std::max_element(wall.begin(), wall.end()), Median(simulated),
                *std::max_element(simulated.begin(), simulated.end()));
    if (resim) {
      std::printf(
          "resimulated 1 s: median %.2f mm, worst %.2f mm; piles declared at rest that moved "
          "more than 0.5 mm: %d of %zu; declared restless: %d\n",
          Median(drift), *std::max_element(drift.begin(), drift.end()), over, rows.size(),
          restless);
    }
    if (picks > 0) {
      std::printf("pick steps: median %.3f s, worst %.3f s wall (%zu steps)\n", Median(pick_wall),
                  *std::max_element(pick_wall.begin(), pick_wall.end()), pick_wall.size());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
} catch (const std::logic_error&) {  // std::stoi on a word that is not a number
  return Usage();
}
