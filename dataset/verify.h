// `cadsynth verify`: an independent check of a BOP dataset cadsynth wrote, that any copy of it can
// be put through (after a transfer, a merge, an edit). It recomputes every label from the files
// as written, by other code paths than the writer's:
//   manifest     every file against manifest.json (size, CRC-32); files it does not list are
//                noted, not failed
//   gt_info      per instance of every image and sensor: px_count_visib and bbox_visib from the
//                mask_visib PNG, px_count_valid from the mask and the depth PNG, bbox_obj and
//                px_count_all from the mask PNG (equal when the box lies in the image; a
//                truncated instance's count and box reach outside it, so the mask's must be the
//                box clipped to the image and the count at most px_count_all), visib_fract, and
//                as bop_toolkit computes them (misc.calc_2d_bbox: width = max - min)
//   coco         every annotation of scene_gt_coco: its RLE decoded against mask_visib, its area
//                and box; and that every instance with a visible pixel has one
//   models_info  the box and diameter (largest distance of two vertices) of each models/ PLY
//   recast       a sample of pixels per image cast as single rays (CGAL's AABB tree, not the
//                renderer's Embree packets) through the PLY models at the poses of scene_gt:
//                each instance's ray must hit it exactly where its mask is on; where mask_visib
//                is on the instance must be the nearest and the exact depth equal to the cast
//                distance; where it is nearest but not visible, something nearer (a tote, a
//                distractor) must show in the depth. Rays that graze an edge (the answer changes
//                within 0.02 px) are not judged.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace cadsynth {

struct VerifyOptions {
  int pixels_per_image = 48;  // re-cast per image and sensor: half on visible masks, half anywhere
  size_t max_problems = 200;  // listed (all are counted)
};

struct VerifyReport {
  struct Check {
    std::string name;  // manifest, gt_info, coco, models_info, recast
    size_t checked = 0, failed = 0;
    std::string unit;  // what `checked` counts: files, instances, annotations, models, pixels
  };
  struct Problem {
    std::string file;    // relative to the dataset
    std::string reason;  // "px_count_visib is 130, mask_visib has 131 pixels"
  };
  std::string dataset;
  std::string run_key;  // the manifest's (empty without one)
  std::vector<Check> checks;
  std::vector<Problem> problems;   // the first max_problems, in file order
  size_t problem_count = 0;        // all of them
  std::vector<std::string> notes;  // facts that are not failures (unlisted files, skipped checks)
  size_t images = 0, instances = 0;

  bool passed() const { return problem_count == 0; }
  // "PASS: 432 images, 1728 instances, 5236 files, 20736 pixels re-cast" or "FAIL: 3 problems
  // (FILE: REASON; ...)".
  std::string Verdict() const;
  // The certificate: dataset, verdict, the run key of the manifest, every check, the problems.
  std::string CertificateJson() const;
};

// Checks the dataset at `root`. Throws Error only when `root` is not a BOP dataset at all (no
// scenes); everything wrong inside one is a Problem.
VerifyReport VerifyDataset(const std::filesystem::path& root, const VerifyOptions& options = {});

}  // namespace cadsynth
