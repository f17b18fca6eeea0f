// Lanes of Embree's 16-ray packets, filled one way for the renderer and the path tracer.
#pragma once

#include <embree3/rtcore.h>
#include <Eigen/Core>

namespace cadsynth {

// Sets lane j of `ray` to start at `origin` along `d` over [tnear, tfar].
inline void SetRayLane(RTCRay16* ray, int j, const Eigen::Vector3f& origin,
                       const Eigen::Vector3f& d, float tnear, float tfar) {
  ray->org_x[j] = origin.x();
  ray->org_y[j] = origin.y();
  ray->org_z[j] = origin.z();
  ray->dir_x[j] = d.x();
  ray->dir_y[j] = d.y();
  ray->dir_z[j] = d.z();
  ray->tnear[j] = tnear;
  ray->tfar[j] = tfar;
  ray->time[j] = 0.0f;
  ray->mask[j] = 0xFFFFFFFFu;  // Debian's Embree is built with ray masks: set every bit
  ray->id[j] = static_cast<unsigned>(j);
  ray->flags[j] = 0;
}

}  // namespace cadsynth
