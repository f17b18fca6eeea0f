// A prepared run as a source of frames: what `generate` renders, one work unit (scene, view) at a
// time, for any caller that wants the frames rather than the files. Generate (generate.h) renders
// through it, and so does the Python module (tools/python/), so frames handed to Python are the
// frames the dataset writer encodes, bit for bit.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "dataset/grasp_labels.h"
#include "recipes/recipe.h"
#include "render/camera.h"
#include "render/frame.h"
#include "tools/pipeline/prepare.h"

namespace cadsynth {

struct FrameSourceOptions {
  // Receives one line per notable fact (what was read, placement, grasps); may be empty.
  std::function<void(const std::string&)> info;
  // The part cache's folder (cad/part_cache.h); none: every part is read and analysed afresh.
  std::optional<std::filesystem::path> cache;
  // A cadsynth executable to read CAD and mesh files in child processes; empty: in this process.
  std::filesystem::path reader;
  // Broken-dataset warnings as errors, and the long stages' progress (PrepareControls).
  bool strict = false;
  StageProgress stage_progress;
};

// One work unit rendered: every sensor of the rig at one view of one scene.
struct RenderedView {
  size_t scene = 0;           // index in the run's scenes (BOP scene_id)
  size_t view = 0;            // index in the run's views (BOP im_id)
  std::vector<Frame> frames;  // one per sensor (FrameSource::sensors()), in order
  // Object pixels visible in the sensor that sees most; the view is written only when this
  // reaches the recipe's min_visible_pixels (`kept`).
  int visible_pixels = 0;
  bool kept = true;
};

// Prepares a run (prepare.h) and renders its work units on demand. Unit g is view g % views() of
// scene g / views(); a shard I/N owns the units with g % N == I. Render() may be called from many
// threads; each scene's renderer is built on first use and kept until ReleaseScene() or until two
// other scenes have been asked for since.
class FrameSource {
 public:
  // Checks the camera, sweep and sampler options, prepares the parts and scenes (the slow part:
  // CAD reading, variants, piles) and plans the views. Throws Error.
  FrameSource(const RunSpec& spec, const FrameSourceOptions& options = {});
  ~FrameSource();
  FrameSource(const FrameSource&) = delete;
  FrameSource& operator=(const FrameSource&) = delete;

  const RunSpec& spec() const { return spec_; }
  const PreparedRun& prepared() const { return prepared_; }
  const std::vector<SweepView>& views() const { return views_; }
  const std::vector<RigSensor>& sensors() const { return sensors_; }
  size_t scenes() const { return prepared_.scenes.size(); }
  size_t units() const { return scenes() * views_.size(); }

  // Renders unit `unit` (< units()) exactly as `generate` does.
  RenderedView Render(size_t unit) const;
  // Builds scene `scene`'s renderer now (with every thread: call it outside parallel work).
  void BuildScene(size_t scene) const;
  // Frees scene `scene`'s renderer (it is built again if asked for).
  void ReleaseScene(size_t scene) const;

  // Grasps (`grasps:` on): every object's grasps in its model frame, sampled on first use, and
  // each scene's placed on its instances, filtered against the scene (once per scene). The
  // references stay valid for the source's lifetime. Throws Error without `grasps:`.
  const std::vector<std::vector<ParallelJawGrasp>>& ObjectJawGrasps() const;
  const std::vector<std::vector<SuctionGrasp>>& ObjectSuctionGrasps() const;
  const SceneGrasps& PlacedGrasps(size_t scene) const;

 private:
  struct SceneState;
  struct GraspState;
  std::shared_ptr<const SceneState> Scene(size_t scene) const;
  void SampleGraspsOnce() const;

  RunSpec spec_;
  FrameSourceOptions options_;
  PreparedRun prepared_;
  std::vector<SweepView> views_;
  std::vector<RigSensor> sensors_;
  std::unique_ptr<GraspState> grasps_;
  struct Cache;
  std::unique_ptr<Cache> cache_;
};

}  // namespace cadsynth
