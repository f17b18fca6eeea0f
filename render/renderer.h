// Ray casting of a Scene with Embree: RGB, depth, visible instance ids and amodal masks.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "cad/part.h"
#include "render/camera.h"
#include "render/frame.h"
#include "render/scene.h"

namespace cadsynth {

struct RenderOptions {
  // Pixel rows handed to one task; results never depend on it or on the thread count.
  int rows_per_task = 8;

  bool Check(std::string* why) const;
};

// Builds the acceleration structures once; Render() may then be called from many threads.
// One ray per pixel through its centre; depth is the camera-frame z of the first hit. The full
// (amodal) silhouette of each instance comes from tracing that instance alone.
class Renderer {
 public:
  // `parts` are copied into the renderer's own buffers; `scene.instances` refer to them by index.
  Renderer(const std::vector<Part>& parts, const Scene& scene, const RenderOptions& options = {});
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  Frame Render(const Camera& camera) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cadsynth
