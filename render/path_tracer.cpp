#include "render/path_tracer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "cad/core/error.h"
#include "cad/core/random.h"
#include "render/bsdf.h"
#include "render/image.h"
#include "render/ray_packet.h"
#include "render/sampling.h"

namespace cadsynth {

namespace {

constexpr unsigned kInvalid = RTC_INVALID_GEOMETRY_ID;
constexpr float kInf = std::numeric_limits<float>::infinity();
// Sampler dimensions of a camera path's aperture point and time (far above the bounces' 1 + 3 b,
// so that switching depth of field or motion blur on changes no other number of a path).
constexpr uint32_t kLensDimension = 1000, kTimeDimension = 1001;
// Powers meet lengths here: a light's numbers are per m^2, the scene's lengths are mm.
constexpr float kMm2PerM2 = 1e6f;

// 1 - cos(theta) for sin^2(theta) = s2, without cancellation for small angles.
float OneMinusCos(float s2) { return s2 / (1 + std::sqrt(std::max(0.0f, 1 - s2))); }

float SmoothStep01(float t) {
  t = std::clamp(t, 0.0f, 1.0f);
  return t * t * (3 - 2 * t);
}

// A light ready for sampling from points of the scene (mm, float).
struct PreparedLight {
  LightSource::Kind kind;
  bool delta = false;
  Eigen::Vector3f position, normal;  // normal: the side it shines to (rect, disc); spot axis
  Eigen::Vector3f axis_u, axis_v;    // rect: half sides; disc: unit axes of its plane
  // rect: the unit directions of axis_u and axis_v, their lengths, and the corner at
  // position - axis_u - axis_v
  Eigen::Vector3f unit_u, unit_v, corner;
  float half_u = 0, half_v = 0;
  float radius = 0, area = 0;  // sphere or disc radius; rect or disc area (mm^2)
  Eigen::Vector3f radiance = Eigen::Vector3f::Zero();  // W/(m^2 sr), for area-like lights
  // Delta lights: point and spot intensity times 1e6 (irradiance = intensity / d_mm^2); the
  // parallel sun's irradiance.
  Eigen::Vector3f intensity = Eigen::Vector3f::Zero();
  float cos_half_spot = -1, spot_smooth = 0;  // spot mask
  Eigen::Vector3f to_sun;                     // sun: unit, towards it
  float sun_cos_max = 1, sun_one_minus_cos = 0;
  // The importance estimate (Importance below): the light's luminous strength (area-like:
  // radiance times area, W/sr per 1e-6; delta: intensity; sun: irradiance) and the radius of a
  // sphere around `position` that holds the whole light (mm).
  float strength = 0, bound_radius = 0;
  float sun_sin_half = 0;  // sun: sine of its angular radius

  // The spot's mask for light leaving its centre along unit direction `out`.
  float Spot(const Eigen::Vector3f& out) const {
    if (kind != LightSource::Kind::kSpot) return 1.0f;
    const float c = out.dot(normal);
    if (c <= cos_half_spot) return 0.0f;
    return spot_smooth > 0 ? SmoothStep01((c - cos_half_spot) / spot_smooth) : 1.0f;
  }
};

PreparedLight Prepare(const LightSource& s) {
  PreparedLight l;
  l.kind = s.kind;
  l.position = s.position.cast<float>();
  const Eigen::Vector3f color = s.color;
  const float power = static_cast<float>(s.power);
  l.normal = s.direction.normalized().cast<float>();
  using K = LightSource::Kind;
  switch (s.kind) {
    case K::kPoint:
    case K::kSpot: {
      l.radius = static_cast<float>(s.radius_mm);
      if (l.radius > 0) {
        // A sphere of radiance P / (4 pi^2 r^2): its intensity seen from afar is P / (4 pi).
        l.radiance = color * power * kMm2PerM2 / (4 * kPiF * kPiF * l.radius * l.radius);
      } else {
        l.delta = true;
        l.intensity = color * power * kMm2PerM2 / (4 * kPiF);
      }
      l.strength = Luminance(l.delta ? l.intensity
                                     : Eigen::Vector3f(l.radiance * kPiF * l.radius * l.radius));
      l.bound_radius = l.radius;
      const double half = 0.5 * s.spot_size_rad;
      l.cos_half_spot = static_cast<float>(std::cos(half));
      l.spot_smooth = static_cast<float>((1 - std::cos(half)) * s.spot_blend);
      break;
    }
    case K::kRect:
    case K::kDisc: {
      Eigen::Vector3f x = s.x_axis.cast<float>();
      x -= x.dot(l.normal) * l.normal;
      if (x.norm() < 1e-3f) {
        x = Eigen::Vector3f::UnitY() - l.normal.y() * l.normal;
        if (x.norm() < 1e-3f) x = Eigen::Vector3f::UnitX() - l.normal.x() * l.normal;
      }
      x.normalize();
      const Eigen::Vector3f y = l.normal.cross(x);
      if (s.kind == K::kRect) {
        l.axis_u = x * static_cast<float>(0.5 * s.size_x_mm);
        l.axis_v = y * static_cast<float>(0.5 * s.size_y_mm);
        l.area = static_cast<float>(s.size_x_mm * s.size_y_mm);
        l.unit_u = x;
        l.unit_v = y;
        l.half_u = static_cast<float>(0.5 * s.size_x_mm);
        l.half_v = static_cast<float>(0.5 * s.size_y_mm);
        l.corner = l.position - l.axis_u - l.axis_v;
      } else {
        l.axis_u = x;
        l.axis_v = y;
        l.radius = static_cast<float>(s.radius_mm);
        l.area = kPiF * l.radius * l.radius;
      }
      // Blender's area light of power P: radiance L = P / (4 A) (Cycles' 0.25 / area), so that it
      // emits pi P / 4 watts, not P: Blender's Watt for area lights, which its scenes are lit by.
      l.radiance = color * power * kMm2PerM2 / (4 * l.area);
      l.strength = Luminance(l.radiance) * l.area;
      l.bound_radius = s.kind == K::kRect ? (l.axis_u + l.axis_v).norm() : l.radius;
      break;
    }
    case K::kSun: {
      l.to_sun = -l.normal;
      const double half = 0.5 * s.angle_rad;
      if (half > 0) {
        const double sin_half = std::sin(half);
        l.sun_cos_max = static_cast<float>(std::cos(half));
        l.sun_one_minus_cos = static_cast<float>(1 - std::cos(half));
        if (l.sun_one_minus_cos <= 0) l.sun_one_minus_cos = static_cast<float>(0.5 * half * half);
        // A disc of uniform radiance L and angular radius a gives E = pi L sin^2(a) facing it.
        l.radiance = color * static_cast<float>(s.power / (M_PI * sin_half * sin_half));
      } else {
        l.delta = true;
        l.intensity = color * power;
      }
      l.strength = Luminance(color) * power;
      l.sun_sin_half = static_cast<float>(std::sin(half));
      break;
    }
  }
  return l;
}

// The direction of anisotropic highlights at point p of an object (its own frame: the model's,
// or the world's for fixtures and the floor) whose bounding box has `centre` and `size`
// (Material::Tangent). Radial: Cycles' default tangent, (-y, x, 0) of the box-normalised
// coordinates about the centre, which the shading frame then projects onto the surface; near the
// axis, where it vanishes, the frame picks any tangent.
Eigen::Vector3f TangentAt(const Material& m, const Eigen::Vector3f& p,
                          const Eigen::Vector3f& centre, const Eigen::Vector3f& size) {
  if (m.tangent == Material::Tangent::kModelX) return Eigen::Vector3f::UnitX();
  const float gx = (p.x() - centre.x()) / std::max(size.x(), 1e-6f);
  const float gy = (p.y() - centre.y()) / std::max(size.y(), 1e-6f);
  return Eigen::Vector3f(-gy, gx, 0.0f);
}

// A cosine that may reach cos(theta - alpha) over directions within alpha of the one at
// cos(theta): min(1, cos(theta) + sin(alpha)) (an upper bound for theta up to 90 degrees), 0 at
// or below 0.
float CosBound(float cos_theta, float sin_alpha) {
  return std::clamp(cos_theta + sin_alpha, 0.0f, 1.0f);
}

// An estimate of the irradiance (luminance, W/m^2) light `l` can give a surface at p with normal
// n, from the light's bounding sphere: the cosines at both ends are loosened by the angle the
// light covers (so a large panel low over a surface is not rated zero), and the distance is at
// least the light's radius. Only the light selection uses it (any positive rating is unbiased).
float Importance(const PreparedLight& l, const Eigen::Vector3f& p, const Eigen::Vector3f& n) {
  using K = LightSource::Kind;
  if (l.kind == K::kSun) return l.strength * CosBound(n.dot(l.to_sun), l.sun_sin_half);
  const Eigen::Vector3f d = l.position - p;
  const float d2 = d.squaredNorm();
  if (!(d2 > 0)) return l.strength;
  const float inv_dist = 1.0f / std::sqrt(d2);
  const float sin_alpha = std::min(1.0f, l.bound_radius * inv_dist);
  const float cos_receiver = n.dot(d) * inv_dist;
  float value = l.strength * CosBound(cos_receiver, sin_alpha) /
                std::max(d2, l.bound_radius * l.bound_radius);
  if (l.kind == K::kRect || l.kind == K::kDisc) {
    value *= CosBound(-d.dot(l.normal) * inv_dist, sin_alpha);  // one-sided emitters
  } else if (l.kind == K::kSpot) {
    value *= l.Spot(-d * inv_dist);
  }
  return value;
}

// A rectangular light as seen from a point: the spherical rectangle it covers (Urena, Fajardo
// and King 2013, "An area-preserving parametrization for spherical rectangles"), for sampling
// directions uniformly in its solid angle. Sampling by area instead weights each point by
// cos / d^2, which varies over a panel that is large and near (a work cell's light over its
// parts), and that variation is noise; sampled by solid angle only the receiver's cosine and
// the visibility are left. The solid angle is a small difference of angles near pi / 2: its
// angles are taken in float where it is large (float's error in it below 1e-3 of it), in double
// below kFloatSolidAngle, and sampling is in double. Far-away panels (solid angle below
// kMinSolidAngle) are sampled by area in both SampleLight and HitLight, where the two ways agree
// and the angles lose precision.
struct SphericalRect {
  static constexpr double kMinSolidAngle = 1e-5;
  // Below this solid angle the four angles are summed in double (their sum's cancellation).
  static constexpr float kFloatSolidAngle = 1e-3f;
  Eigen::Vector3d o, x, y, z;  // the point; the light's unit axes; z its normal
  double x0, x1, y0, y1, z0;   // the rectangle in that frame, z0 < 0
  double b0, b1, k, solid_angle;

  // False when o is behind the light's plane (or in it).
  bool Init(const PreparedLight& l, const Eigen::Vector3f& point) {
    // In the light's frame: the rectangle spans [x0, x1] x [y0, y1] at height z0 below o. The
    // planes through o and each edge have normals n0 = (0, z0, -y0) / a0, n1 = (-z0, 0, x1) / a1,
    // n2 = (0, -z0, y1) / a2, n3 = (z0, 0, -x0) / a3 (the cross products of the corners'
    // directions, a_i their lengths), and the angles between them are the spherical
    // rectangle's: g_i = acos(-n_i . n_(i+1)).
    const Eigen::Vector3f d = l.corner - point;
    const float fz0 = d.dot(l.normal);
    if (!(fz0 < 0)) return false;
    const float fx0 = d.dot(l.unit_u), fy0 = d.dot(l.unit_v);
    const float fx1 = fx0 + 2 * l.half_u, fy1 = fy0 + 2 * l.half_v;
    x0 = fx0, x1 = fx1, y0 = fy0, y1 = fy1, z0 = fz0;
    Angles<float>();
    if (solid_angle < kFloatSolidAngle) Angles<double>();  // small and far: the same in double
    o = point.cast<double>();
    x = l.unit_u.cast<double>();
    y = l.unit_v.cast<double>();
    z = l.normal.cast<double>();
    return true;
  }

  // The angles of the rectangle [x0, x1] x [y0, y1] at z0, in T: b0, b1, k and the solid angle.
  template <typename T>
  void Angles() {
    const T xa = static_cast<T>(x0), xb = static_cast<T>(x1), ya = static_cast<T>(y0),
            yb = static_cast<T>(y1), za = static_cast<T>(z0);
    const T zz = za * za;
    const T r0 = 1 / std::sqrt(zz + ya * ya), r1 = 1 / std::sqrt(zz + xb * xb),
            r2 = 1 / std::sqrt(zz + yb * yb), r3 = 1 / std::sqrt(zz + xa * xa);
    const auto angle = [](T c) { return std::acos(std::clamp(c, T(-1), T(1))); };
    const T g0 = angle(ya * xb * r0 * r1), g1 = angle(-xb * yb * r1 * r2),
            g2 = angle(xa * yb * r2 * r3), g3 = angle(-xa * ya * r3 * r0);
    b0 = -ya * r0;
    b1 = yb * r2;
    k = 2 * M_PI - g2 - g3;
    solid_angle = static_cast<double>(g0) + g1 - k;
  }

  // The point of the rectangle in direction (u, v) of the unit square, uniform in solid angle.
  Eigen::Vector3d Sample(const Eigen::Vector2f& uv) const {
    const double au = uv.x() * solid_angle + k;
    const double s = std::sin(au);
    const double fu = s != 0 ? (std::cos(au) * b0 - b1) / s : 0.0;
    double cu = std::copysign(1.0, fu) / std::sqrt(fu * fu + b0 * b0);
    cu = std::clamp(cu, -1.0, 1.0);
    const double xu = std::clamp(-(cu * z0) / std::max(1e-12, std::sqrt(1 - cu * cu)), x0, x1);
    const double dist = std::sqrt(xu * xu + z0 * z0);
    const double h0 = y0 / std::sqrt(dist * dist + y0 * y0);
    const double h1 = y1 / std::sqrt(dist * dist + y1 * y1);
    const double hv = h0 + uv.y() * (h1 - h0), hv2 = hv * hv;
    const double yv = hv2 < 1 - 1e-12 ? std::clamp(hv * dist / std::sqrt(1 - hv2), y0, y1) : y1;
    return o + xu * x + yv * y + z0 * z;
  }
};

struct LightSample {
  Eigen::Vector3f wi;
  float distance = kInf;  // to the emitting point (shadow ray length)
  Eigen::Vector3f value;  // radiance, or for delta lights the irradiance normal to wi
  float pdf = 1;          // solid angle density (1 for delta lights)
};

// Samples a direction towards `l` from point p. False when the light cannot reach p.
bool SampleLight(const PreparedLight& l, const Eigen::Vector3f& p, const Eigen::Vector2f& u,
                 LightSample* out) {
  using K = LightSource::Kind;
  switch (l.kind) {
    case K::kPoint:
    case K::kSpot: {
      const Eigen::Vector3f d = l.position - p;
      const float d2 = d.squaredNorm();
      const float dist = std::sqrt(d2);
      if (!(dist > 0)) return false;
      const Eigen::Vector3f to_light = d / dist;
      const float spot = l.Spot(-to_light);
      if (spot <= 0) return false;
      if (l.delta) {
        out->wi = to_light;
        out->distance = dist;
        out->value = l.intensity * (spot / d2);
        out->pdf = 1;
        return true;
      }
      const float s2 = l.radius * l.radius / d2;
      if (s2 >= 1) return false;  // inside the sphere
      const float one_minus_cos = OneMinusCos(s2);
      Eigen::Vector3f t, b;
      OrthonormalBasis(to_light, &t, &b);
      const Eigen::Vector3f local = UniformCone(u, 1 - one_minus_cos);
      out->wi = (local.x() * t + local.y() * b + local.z() * to_light).normalized();
      // Distance to the sphere's near side along wi.
      const float proj = out->wi.dot(d);
      const float disc = proj * proj - (d2 - l.radius * l.radius);
      out->distance = proj - std::sqrt(std::max(0.0f, disc));
      out->value = l.radiance * spot;
      out->pdf = 1 / (2 * kPiF * one_minus_cos);
      return true;
    }
    case K::kRect:
    case K::kDisc: {
      Eigen::Vector3f q;
      if (l.kind == K::kRect) {
        SphericalRect rect;
        if (!rect.Init(l, p)) return false;  // behind the light
        if (rect.solid_angle >= SphericalRect::kMinSolidAngle) {
          const Eigen::Vector3d d = rect.Sample(u) - rect.o;
          const double dist = d.norm();
          if (!(dist > 0)) return false;
          out->wi = (d / dist).cast<float>();
          out->distance = static_cast<float>(dist);
          out->value = l.radiance;
          out->pdf = static_cast<float>(1 / rect.solid_angle);
          return true;
        }
        q = l.position + (2 * u.x() - 1) * l.axis_u + (2 * u.y() - 1) * l.axis_v;
      } else {
        const Eigen::Vector2f d = ConcentricDisc(u) * l.radius;
        q = l.position + d.x() * l.axis_u + d.y() * l.axis_v;
      }
      const Eigen::Vector3f d = q - p;
      const float d2 = d.squaredNorm();
      const float dist = std::sqrt(d2);
      if (!(dist > 0)) return false;
      out->wi = d / dist;
      const float cos_light = -out->wi.dot(l.normal);
      if (cos_light <= 0) return false;  // behind the light
      out->distance = dist;
      out->value = l.radiance;
      out->pdf = d2 / (l.area * cos_light);
      return true;
    }
    case K::kSun: {
      out->distance = kInf;
      if (l.delta) {
        out->wi = l.to_sun;
        out->value = l.intensity;
        out->pdf = 1;
        return true;
      }
      Eigen::Vector3f t, b;
      OrthonormalBasis(l.to_sun, &t, &b);
      const Eigen::Vector3f local = UniformCone(u, l.sun_cos_max);
      out->wi = (local.x() * t + local.y() * b + local.z() * l.to_sun).normalized();
      out->value = l.radiance;
      out->pdf = 1 / (2 * kPiF * l.sun_one_minus_cos);
      return true;
    }
  }
  return false;
}

// Where a ray (unit direction) meets an area-like light before tmax: distance, radiance and the
// solid-angle density SampleLight would have picked that direction with. Delta lights are never
// hit; the sun only by rays that escape (tmax infinite).
bool HitLight(const PreparedLight& l, const Eigen::Vector3f& o, const Eigen::Vector3f& dir,
              float tmax, Eigen::Vector3f* radiance, float* pdf) {
  if (l.delta) return false;
  using K = LightSource::Kind;
  switch (l.kind) {
    case K::kPoint:
    case K::kSpot: {
      const Eigen::Vector3f d = l.position - o;
      const float d2 = d.squaredNorm();
      const float r2 = l.radius * l.radius;
      if (d2 <= r2) return false;
      const float proj = dir.dot(d);
      if (proj <= 0) return false;
      const float disc = proj * proj - (d2 - r2);
      if (disc < 0) return false;
      const float t = proj - std::sqrt(disc);
      if (!(t > 0 && t < tmax)) return false;
      const float spot = l.Spot(-(d / std::sqrt(d2)));
      if (spot <= 0) return false;
      *radiance = l.radiance * spot;
      *pdf = 1 / (2 * kPiF * OneMinusCos(r2 / d2));
      return true;
    }
    case K::kRect:
    case K::kDisc: {
      const float denom = dir.dot(l.normal);
      if (denom >= 0) return false;  // the back or the edge: area lights shine one way
      const float t = (l.position - o).dot(l.normal) / denom;
      if (!(t > 0 && t < tmax)) return false;
      const Eigen::Vector3f q = o + t * dir - l.position;
      if (l.kind == K::kRect) {
        if (std::abs(q.dot(l.axis_u)) > l.axis_u.squaredNorm() ||
            std::abs(q.dot(l.axis_v)) > l.axis_v.squaredNorm()) {
          return false;
        }
      } else if (q.squaredNorm() > l.radius * l.radius) {
        return false;
      }
      *radiance = l.radiance;
      *pdf = t * t / (l.area * -denom);
      if (l.kind == K::kRect) {
        SphericalRect rect;
        if (rect.Init(l, o) && rect.solid_angle >= SphericalRect::kMinSolidAngle) {
          *pdf = static_cast<float>(1 / rect.solid_angle);
        }
      }
      return true;
    }
    case K::kSun: {
      if (tmax < kInf || dir.dot(l.to_sun) < l.sun_cos_max) return false;
      *radiance = l.radiance;
      *pdf = 1 / (2 * kPiF * l.sun_one_minus_cos);
      return true;
    }
  }
  return false;
}

// The environment: evaluation, and for an image (the only kind next-event estimation samples)
// sampling in proportion to its pixels' luminance times their solid angle.
class PreparedEnvironment {
 public:
  // `like`: an environment prepared before whose image's sampling tables can be shared (the
  // same pixels: only strength or rotation differ).
  explicit PreparedEnvironment(const Environment& e, const PreparedEnvironment* like = nullptr)
      : env_(e) {
    if (e.kind == Environment::Kind::kImage) {
      if (like != nullptr && like->image_ && like->image_ == e.pixels) {
        image_ = like->image_;
        tables_ = like->tables_;
      } else {
        image_ = e.pixels;
        if (!image_) image_ = LoadLinearImage(e.image);
        BuildDistribution();
      }
    }
    black_ = e.strength <= 0 ||
             (e.kind == Environment::Kind::kUniform && e.color.maxCoeff() <= 0) ||
             (e.kind == Environment::Kind::kSky && e.zenith.maxCoeff() <= 0 &&
              e.horizon.maxCoeff() <= 0 && e.ground.maxCoeff() <= 0) ||
             (e.kind == Environment::Kind::kImage && tables_->total <= 0);
    if (e.kind == Environment::Kind::kImage) {
      // sum of lum sin(theta) over pixels of (pi / h) x (2 pi / w), over 4 pi.
      mean_luminance_ =
          tables_->total * kPiF / (2.0f * image_->width * image_->height) * e.strength;
    }
  }
  bool black() const { return black_; }
  // Whether next-event estimation samples it: an image only. A uniform or sky environment
  // changes slowly with direction, so the BSDF's own sample finds it as well as a light sample
  // would (drawn cosine-weighted about the normal, the diffuse lobe's own distribution) and
  // better on a glossy lobe, where a cosine-weighted direction landed in the lobe's tail now and
  // then with a large weight. Cycles too leaves a world without spatial
  // variation out of its light sampling ("Background MIS has been disabled").
  bool sampled() const { return env_.kind == Environment::Kind::kImage; }
  // A sampled environment's mean radiance's luminance over all directions (W/(m^2 sr)).
  float MeanLuminance() const { return mean_luminance_; }

  Eigen::Vector3f Eval(const Eigen::Vector3f& d) const {
    switch (env_.kind) {
      case Environment::Kind::kUniform:
        return env_.color * env_.strength;
      case Environment::Kind::kSky: {
        if (d.z() < 0) return env_.ground * env_.strength;
        const float t = std::sqrt(std::min(1.0f, d.z()));
        return ((1 - t) * env_.horizon + t * env_.zenith) * env_.strength;
      }
      case Environment::Kind::kImage:
        return Bilinear(d) * env_.strength;
    }
    return Eigen::Vector3f::Zero();
  }

  // A sampled (image) environment only: a direction in proportion to the pixels' luminance
  // times their solid angle, and its density.
  Eigen::Vector3f Sample(const Eigen::Vector2f& u, float* pdf) const {
    const int w = image_->width, h = image_->height;
    const Tables& t = *tables_;
    // Row by the marginal distribution, then the column within it.
    const int y = static_cast<int>(std::min<size_t>(
        std::upper_bound(t.row_cdf.begin(), t.row_cdf.end(), u.y() * t.total) - t.row_cdf.begin(),
        static_cast<size_t>(h - 1)));
    const float* cdf = &t.col_cdf[static_cast<size_t>(y) * w];
    const float row_total = cdf[w - 1];
    const int x = static_cast<int>(
        std::min<ptrdiff_t>(std::upper_bound(cdf, cdf + w, u.x() * row_total) - cdf, w - 1));
    // A point inside the pixel: reuse what is left of the numbers.
    const float row_lo = y > 0 ? t.row_cdf[y - 1] : 0.0f;
    const float col_lo = x > 0 ? cdf[x - 1] : 0.0f;
    const float fy = std::clamp((u.y() * t.total - row_lo) / (t.row_cdf[y] - row_lo), 0.0f, 1.0f);
    const float fx = std::clamp((u.x() * row_total - col_lo) / (cdf[x] - col_lo), 0.0f, 1.0f);
    const float theta = kPiF * (y + fy) / h;
    const float uu = (x + fx) / w;
    const float phi = 2 * kPiF * (0.5f - uu) - static_cast<float>(env_.rotation_rad);
    const Eigen::Vector3f d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                            std::cos(theta));
    *pdf = Pdf(d);
    return d;
  }

  float Pdf(const Eigen::Vector3f& d) const {
    const auto [x, y] = Pixel(d);
    const float sin_theta = std::sqrt(std::max(0.0f, 1 - d.z() * d.z()));
    const Tables& t = *tables_;
    if (sin_theta <= 0 || t.total <= 0) return 0.0f;
    // Density on the unit square is weight * w * h / total; dOmega = 2 pi^2 sin(theta) du dv.
    const float p_uv = t.weight[static_cast<size_t>(y) * image_->width + x] * image_->width *
                       image_->height / t.total;
    return p_uv / (2 * kPiF * kPiF * sin_theta);
  }

 private:
  // The image's (u, v) in [0, 1) x [0, 1] of direction d: the image is looked up at d turned by
  // `rotation` about z (Blender's Mapping node rotation before an Environment Texture;
  // BlenderProc's rotation_euler z), so its content turns by -rotation.
  Eigen::Vector2f Uv(const Eigen::Vector3f& d) const {
    const float phi = std::atan2(d.y(), d.x()) + static_cast<float>(env_.rotation_rad);
    float u = 0.5f - phi / (2 * kPiF);
    u -= std::floor(u);
    return {u, std::acos(std::clamp(d.z(), -1.0f, 1.0f)) / kPiF};
  }
  // The pixel holding direction d (the sampling tables' cell).
  std::pair<int, int> Pixel(const Eigen::Vector3f& d) const {
    const Eigen::Vector2f uv = Uv(d);
    const int x = std::clamp(static_cast<int>(uv.x() * image_->width), 0, image_->width - 1);
    const int y = std::clamp(static_cast<int>(uv.y() * image_->height), 0, image_->height - 1);
    return {x, y};
  }
  // The radiance along d, interpolated between pixel centres (Blender's Linear interpolation),
  // wrapping around in u. The sampling tables weigh each pixel by this function's integral over
  // it, so the density is positive wherever the radiance is.
  Eigen::Vector3f Bilinear(const Eigen::Vector3f& d) const {
    const int w = image_->width, h = image_->height;
    const Eigen::Vector2f uv = Uv(d);
    const float x = uv.x() * w - 0.5f;
    const float y = std::clamp(uv.y() * h - 0.5f, 0.0f, static_cast<float>(h - 1));
    const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(y);
    const int y1 = std::min(y0 + 1, h - 1);
    const float fx = x - x0, fy = y - y0;
    const int xa = (x0 % w + w) % w, xb = ((x0 + 1) % w + w) % w;
    const auto at = [&](int xi, int yi) {
      const float* c = image_->at(xi, yi);
      return Eigen::Vector3f(c[0], c[1], c[2]);
    };
    return (1 - fy) * ((1 - fx) * at(xa, y0) + fx * at(xb, y0)) +
           fy * ((1 - fx) * at(xa, y1) + fx * at(xb, y1));
  }

  void BuildDistribution() {
    const int w = image_->width, h = image_->height;
    auto tables = std::make_shared<Tables>();
    std::vector<float>&weight = tables->weight, &col_cdf = tables->col_cdf,
    &row_cdf = tables->row_cdf;
    weight.resize(static_cast<size_t>(w) * h);
    col_cdf.resize(weight.size());
    row_cdf.resize(h);
    // Each pixel's weight is the integral over it of the image as Bilinear() interpolates it: the
    // luminances filtered by [1/8, 3/4, 1/8] along both axes (wrapping around in x, the edge rows
    // repeated in y), so that a dark pixel beside a small bright sun, which the interpolation
    // lights, is sampled too.
    std::vector<float> lum(static_cast<size_t>(w) * h), across(lum.size());
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const float* c = image_->at(x, y);
        lum[static_cast<size_t>(y) * w + x] =
            std::max(0.0f, Luminance(Eigen::Vector3f(c[0], c[1], c[2])));
      }
    }
    for (int y = 0; y < h; ++y) {
      const float* row = &lum[static_cast<size_t>(y) * w];
      for (int x = 0; x < w; ++x) {
        across[static_cast<size_t>(y) * w + x] =
            0.125f * row[(x + w - 1) % w] + 0.75f * row[x] + 0.125f * row[(x + 1) % w];
      }
    }
    double total = 0;
    for (int y = 0; y < h; ++y) {
      const float sin_theta = std::sin(kPiF * (y + 0.5f) / h);
      const float* up = &across[static_cast<size_t>(std::max(y - 1, 0)) * w];
      const float* mid = &across[static_cast<size_t>(y) * w];
      const float* down = &across[static_cast<size_t>(std::min(y + 1, h - 1)) * w];
      double row = 0;
      for (int x = 0; x < w; ++x) {
        const size_t i = static_cast<size_t>(y) * w + x;
        weight[i] = (0.125f * up[x] + 0.75f * mid[x] + 0.125f * down[x]) * sin_theta;
        row += weight[i];
        col_cdf[i] = static_cast<float>(row);
      }
      total += row;
      row_cdf[y] = static_cast<float>(total);
    }
    tables->total = static_cast<float>(total);
    tables_ = std::move(tables);
  }

  // An image's sampling tables: per pixel luminance times sin(theta), each row's running sum,
  // and the rows' running sum.
  struct Tables {
    std::vector<float> weight, col_cdf, row_cdf;
    float total = 0;
  };
  Environment env_;
  std::shared_ptr<const LinearImage> image_;
  std::shared_ptr<const Tables> tables_;
  bool black_ = false;
  float mean_luminance_ = 0;
};

}  // namespace

uint64_t FrameSeed(int seed, uint64_t view) {
  return Hash(Hash(streams::kRenderPixel.id(), static_cast<uint64_t>(seed)), view);
}

float FilmicCurve(float x) {
  x = std::max(0.0f, x);
  return std::min(1.0f, x * (2.51f * x + 0.03f) / (x * (2.43f * x + 0.59f) + 0.14f));
}

float DisplayValue(float linear, bool filmic) {
  return LinearToSrgb(filmic ? FilmicCurve(linear) : linear);
}

struct PathTracer::Impl {
  PathTracerScene scene;
  std::vector<PreparedLight> lights;
  std::optional<PreparedEnvironment> environment;  // absent when black
  bool environment_sampled = false;                // a strategy of next-event estimation
  int num_strategies = 0;                          // lights + a sampled environment
  // Whether strategies are rated (SelectionPdfs; at most kMaxRated), and the even probability.
  bool rated = true;
  float even_pdf = 0;
  float environment_importance = 0;  // pi times its mean luminance (W/m^2)
  std::vector<std::shared_ptr<const LinearImage>> instance_images;
  std::shared_ptr<const LinearImage> floor_image;
  std::vector<std::shared_ptr<const LinearImage>> fixture_images;

  struct Surface {
    Eigen::Vector3f p, ng, ns;
    Eigen::Vector3f tangent = Eigen::Vector3f::UnitX();  // set for anisotropic materials only
    PrincipledParams params;
    float cone_width = 0;  // mm: the width of the ray cone at p
  };
  // The surface a ray hit: its point, normals facing the ray, and textured material. The ray
  // stands for a cone (Amanatides 1984) of width `width` mm at its origin widening by `spread`
  // per mm; textures are filtered over its footprint on the surface.
  Surface Hit(const RTCRayHit16& rh, int j, const Eigen::Vector3f& dir, float width,
              float spread) const;

  // Next-event estimation picks one strategy (a light, or a sampled environment: index
  // lights.size()) per surface point, with probability pdf[k]: nine tenths in proportion to an
  // estimate of what each gives the point (its definition below: bright and near lights, and those
  // a glossy lobe sees, get the samples), one tenth evenly (so that nothing that can light p is
  // starved by a poor estimate). Evenly when more than kMaxRated strategies. The BSDF's sample
  // leaving the same point reuses the numbers for its MIS weights when it finds a light or the sky.
  static constexpr int kMaxRated = 32;
  // The point a strategy is rated for: position, shading normal and frame, the direction towards
  // the viewer (world and the frame's) and its BSDF.
  struct Receiver {
    Eigen::Vector3f p, n, wo_world, wo;
    const Eigen::Vector3f *t, *b;
    const PrincipledBsdf* bsdf;
  };
  void SelectionPdfs(const Receiver& r, float* pdf) const;

  // The BSDF's frame at a surface: the shading normal, and a tangent along the brushing
  // direction for anisotropic materials (any tangent otherwise).
  struct ShadingFrame {
    Eigen::Vector3f t, b, n;
    explicit ShadingFrame(const Surface& surf) : n(surf.ns) {
      if (surf.params.anisotropic > 0) t = surf.tangent - surf.tangent.dot(n) * n;
      if (surf.params.anisotropic > 0 && t.squaredNorm() > 1e-6f) {
        t.normalize();
        b = n.cross(t);
      } else {
        OrthonormalBasis(n, &t, &b);
      }
    }
    Eigen::Vector3f ToLocal(const Eigen::Vector3f& w) const {
      return Eigen::Vector3f(w.dot(t), w.dot(b), w.dot(n));
    }
  };

  // TraceTile's steps. A packet holds 16 paths of a tile's pixels (Packet, below); each bounce
  // adds the light its segments found (AddEmission), then shades every lane that hit a surface
  // in three passes: each lane's surface, light sample and BSDF direction (SampleLanes), every
  // lane's two BSDF values at once (EvaluateLanes: in SIMD, or one lane at a time for the
  // scalar reference), and the shadow rays and next segments (ContinuePaths, TraceShadows).
  struct CameraRays;
  struct Packet;
  struct PixelSums;
  void TracePacket(const CameraRays& camera, Packet* k) const;
  void StartPaths(const CameraRays& camera, Packet* k) const;
  // Whether any lane hit a surface it shades (depth <= bounces); lanes that did not stop.
  bool AddEmission(Packet* k, int depth) const;
  void SampleLanes(Packet* k, int depth) const;
  void EvaluateLanes(Packet* k) const;
  // Whether any lane goes on.
  bool ContinuePaths(Packet* k, int depth) const;
  void TraceShadows(Packet* k) const;

  // Clamp Indirect (Cycles' kernel_accum_clamp): a contribution of indirect light scaled to an
  // RGB sum of at most scene.clamp_indirect. Light a path's segment `depth` finds is indirect
  // from the third segment on (two bounces before it); a light sample from the second vertex on.
  Eigen::Vector3f ClampIndirect(const Eigen::Vector3f& c) const {
    const float sum = c.cwiseAbs().sum();
    return scene.clamp_indirect > 0 && sum > scene.clamp_indirect
               ? Eigen::Vector3f(c * (scene.clamp_indirect / sum))
               : c;
  }
  Eigen::Vector3f ClampEmission(const Eigen::Vector3f& c, int depth) const {
    return depth >= 2 ? ClampIndirect(c) : c;
  }
};

PathTracer::PathTracer(PathTracerScene scene, const PathTracer* like)
    : impl_(std::make_unique<Impl>()) {
  Impl& im = *impl_;
  im.scene = std::move(scene);
  for (const LightSource& s : im.scene.lights) {
    if (s.power > 0 && s.color.maxCoeff() > 0) im.lights.push_back(Prepare(s));
  }
  const PreparedEnvironment* before =
      like != nullptr && like->impl_->environment ? &*like->impl_->environment : nullptr;
  const PreparedEnvironment env(im.scene.environment, before);
  if (!env.black()) im.environment.emplace(env);
  im.environment_sampled = im.environment && im.environment->sampled();
  im.num_strategies = static_cast<int>(im.lights.size()) + (im.environment_sampled ? 1 : 0);
  im.rated = im.num_strategies <= Impl::kMaxRated;
  im.even_pdf = im.num_strategies > 0 ? 1.0f / im.num_strategies : 0.0f;
  if (im.environment_sampled) im.environment_importance = kPiF * im.environment->MeanLuminance();
  const auto image_of = [](const Material& m) -> std::shared_ptr<const LinearImage> {
    if (m.texture.kind != Texture::Kind::kImage) return nullptr;
    return m.texture.pixels ? m.texture.pixels : LoadLinearImage(m.texture.image);
  };
  for (const TracedInstance& instance : im.scene.instances)
    im.instance_images.push_back(image_of(instance.material));
  im.floor_image = image_of(im.scene.floor);
  for (const TracedFixture& f : im.scene.fixtures)
    im.fixture_images.push_back(image_of(f.material));
}

PathTracer::~PathTracer() = default;

void PathTracer::Impl::SelectionPdfs(const Receiver& r, float* pdf) const {
  const int count = num_strategies;
  if (count == 1) {  // nothing to choose between: no estimate to compute at every vertex
    pdf[0] = 1.0f;
    return;
  }
  const int num_lights = static_cast<int>(lights.size());
  // What each strategy gives the point, about: the light's irradiance bound E times the BSDF
  // towards the light (where the light's bounding cone comes nearest to the mirror direction, so
  // that a glossy lobe's highlight is found even off the light's centre), at least a quarter of a
  // Lambertian surface's albedo / pi (a light the lobe misses still lights the rest), at most the
  // light's radiance times the albedo (what it gives when it fills the lobe). The environment:
  // its mean radiance times the albedo. On a surface that is not Glossy() every rating is
  // E albedo / pi (the BSDF is not evaluated): the lights in proportion to their irradiance.
  const float albedo = r.bsdf->Albedo(r.wo);
  const Eigen::Vector3f mirror = 2 * r.n.dot(r.wo_world) * r.n - r.wo_world;
  const float lambert = albedo / kPiF;
  const bool glossy = r.bsdf->Glossy();
  float total = 0;
  for (int k = 0; k < count; ++k) {
    float w;
    if (k == num_lights) {
      w = environment_importance * lambert;
    } else {
      const PreparedLight& l = lights[k];
      const float e = Importance(l, r.p, r.n);
      if (!(e > 0) || !glossy) {
        w = e * lambert;
      } else {
        // The light's cone as seen from p: its centre direction c and the sine of its radius.
        Eigen::Vector3f c;
        float sin_radius;
        if (l.kind == LightSource::Kind::kSun) {
          c = l.to_sun;
          sin_radius = l.sun_sin_half;
        } else {
          const Eigen::Vector3f d = l.position - r.p;
          const float dist = d.norm();
          c = d / dist;
          sin_radius = std::min(1.0f, l.bound_radius / dist);
        }
        const float cos_cm = c.dot(mirror);
        const float cos_radius = std::sqrt(1 - sin_radius * sin_radius);
        Eigen::Vector3f toward = mirror;
        if (cos_cm < cos_radius) {  // the mirror direction is outside: the cone's nearest edge
          const Eigen::Vector3f across = mirror - cos_cm * c;
          const float norm = across.norm();
          toward =
              norm > 1e-6f ? Eigen::Vector3f(cos_radius * c + (sin_radius / norm) * across) : c;
        }
        const Eigen::Vector3f wi(toward.dot(*r.t), toward.dot(*r.b), toward.dot(r.n));
        const float f = std::max(0.25f * lambert, Luminance(r.bsdf->Eval(r.wo, wi)));
        w = e * f;
        if (!l.delta) w = std::min(w, Luminance(l.radiance) * albedo);
      }
    }
    pdf[k] = std::isfinite(w) ? std::max(0.0f, w) : 0.0f;
    total += pdf[k];
  }
  const float even = 1.0f / static_cast<float>(count);
  if (!(total > 0) || !std::isfinite(total)) {
    for (int k = 0; k < count; ++k) pdf[k] = even;
    return;
  }
  const float scale = 0.9f / total, floor = 0.1f * even;
  for (int k = 0; k < count; ++k) pdf[k] = scale * pdf[k] + floor;
}

PathTracer::Impl::Surface PathTracer::Impl::Hit(const RTCRayHit16& rh, int j,
                                                const Eigen::Vector3f& dir, float width,
                                                float spread) const {
  Surface s;
  // The packet's own direction: camera rays are not unit length (their t is depth).
  s.p = Eigen::Vector3f(rh.ray.org_x[j], rh.ray.org_y[j], rh.ray.org_z[j]) +
        rh.ray.tfar[j] * Eigen::Vector3f(rh.ray.dir_x[j], rh.ray.dir_y[j], rh.ray.dir_z[j]);
  const unsigned inst = rh.hit.instID[0][j];
  const Material* material;
  const LinearImage* image;
  Eigen::Vector3f tex_p, tex_n;
  Eigen::Vector2f uv;
  bool has_uv = false;
  if (inst != kInvalid) {
    const TracedInstance& ti = scene.instances[inst];
    const uint32_t* tri = &ti.indices[3 * rh.hit.primID[j]];
    const float b1 = rh.hit.u[j], b2 = rh.hit.v[j], b0 = 1.0f - b1 - b2;
    // Embree gives an instance's geometric normal in its object frame.
    s.ng = (ti.rotation * Eigen::Vector3f(rh.hit.Ng_x[j], rh.hit.Ng_y[j], rh.hit.Ng_z[j]))
               .normalized();
    s.ns = (ti.rotation *
            (b0 * ti.normals[tri[0]] + b1 * ti.normals[tri[1]] + b2 * ti.normals[tri[2]]))
               .normalized();
    material = &ti.material;
    image = instance_images[inst].get();
    tex_p = ti.rotation.transpose() * (s.p - ti.translation);
    tex_n = ti.rotation.transpose() * s.ns;
    if (material->surface.anisotropic > 0)
      s.tangent = ti.rotation * TangentAt(*material, tex_p, ti.box_centre, ti.box_size);
    if (ti.uvs != nullptr) {
      uv = b0 * ti.uvs[tri[0]] + b1 * ti.uvs[tri[1]] + b2 * ti.uvs[tri[2]];
      has_uv = true;
    }
  } else if (const unsigned geom = rh.hit.geomID[j];
             scene.first_fixture_id != kInvalid && geom >= scene.first_fixture_id &&
             geom - scene.first_fixture_id < scene.fixtures.size()) {
    const size_t f = geom - scene.first_fixture_id;
    const TracedFixture& tf = scene.fixtures[f];
    const uint32_t* tri = &tf.indices[3 * rh.hit.primID[j]];
    const float b1 = rh.hit.u[j], b2 = rh.hit.v[j], b0 = 1.0f - b1 - b2;
    s.ng = Eigen::Vector3f(rh.hit.Ng_x[j], rh.hit.Ng_y[j], rh.hit.Ng_z[j]).normalized();
    s.ns =
        (b0 * tf.normals[tri[0]] + b1 * tf.normals[tri[1]] + b2 * tf.normals[tri[2]]).normalized();
    material = &tf.material;
    if (material->surface.anisotropic > 0)
      s.tangent = TangentAt(*material, s.p, tf.box_centre, tf.box_size);
    image = fixture_images[f].get();
    tex_p = s.p;
    tex_n = s.ns;
  } else {
    s.ng = s.ns = Eigen::Vector3f::UnitZ();
    material = &scene.floor;
    // The floor is a square centred on the origin.
    if (material->surface.anisotropic > 0)
      s.tangent = TangentAt(*material, s.p, Eigen::Vector3f::Zero(), Eigen::Vector3f::Ones());
    image = floor_image.get();
    tex_p = s.p;
    tex_n = s.ns;
  }
  if (!s.ns.allFinite()) s.ns = s.ng;
  if (!s.ng.allFinite()) s.ng = s.ns;
  if (s.ng.dot(dir) > 0) s.ng = -s.ng;  // two-sided: face the incoming ray
  if (s.ns.dot(s.ng) < 0) s.ns = -s.ns, tex_n = -tex_n;
  s.params = material->surface;
  const Eigen::Vector3f origin(rh.ray.org_x[j], rh.ray.org_y[j], rh.ray.org_z[j]);
  s.cone_width = width + spread * (s.p - origin).norm();
  if (material->texture.kind != Texture::Kind::kNone) {
    // The cone's footprint stretches where it meets the surface at a grazing angle.
    const float footprint = s.cone_width / std::max(0.2f, std::abs(dir.dot(s.ng)));
    const TextureSample t =
        EvalTexture(material->texture, tex_p, tex_n, image, footprint, has_uv ? &uv : nullptr);
    s.params = ApplyTexture(material->surface, t);
    if (t.normal_offset.squaredNorm() > 0) {
      // Back to the world frame: instances rotate their texture frame.
      const Eigen::Vector3f offset =
          inst != kInvalid ? Eigen::Vector3f(scene.instances[inst].rotation * t.normal_offset)
                           : t.normal_offset;
      const Eigen::Vector3f bumped = (s.ns + offset).normalized();
      if (bumped.allFinite() && bumped.dot(-dir) > 0 && bumped.dot(s.ng) > 0) s.ns = bumped;
    }
  }
  // A smooth normal turned away from the viewer (silhouettes of coarse meshes): shade flat.
  if (s.ns.dot(-dir) <= 0) s.ns = s.ng;
  return s;
}

void PathTracer::ProjectorSignal(const RTCRayHit16& rh, const int valid[16],
                                 const Eigen::Vector3f& projector, float spread,
                                 float out[16]) const {
  const Impl& im = *impl_;
  for (int j = 0; j < 16; ++j) {
    out[j] = 0.0f;
    if (!valid[j] || rh.hit.geomID[j] == kInvalid) continue;
    const Eigen::Vector3f dir =
        Eigen::Vector3f(rh.ray.dir_x[j], rh.ray.dir_y[j], rh.ray.dir_z[j]).normalized();
    const Impl::Surface surf = im.Hit(rh, j, dir, 0.0f, spread);
    const Eigen::Vector3f to_projector = (projector - surf.p).normalized();
    if (!(to_projector.dot(surf.ng) > 0.0f) || !(to_projector.dot(surf.ns) > 0.0f)) continue;
    const Impl::ShadingFrame local(surf);
    const Eigen::Vector3f wi = local.ToLocal(to_projector);
    const Eigen::Vector3f f = PrincipledBsdf(surf.params).Eval(local.ToLocal(-dir), wi);
    const float signal = static_cast<float>(M_PI) * Luminance(f) * wi.z();
    out[j] = std::isfinite(signal) ? signal : 0.0f;
  }
}

bool AdaptiveSampling::Converged(int n, double sum, double sum_sq, double peak) const {
  if (n < 2) return false;
  const double mean = sum / n;
  double variance = std::max(0.0, sum_sq - n * mean * mean) / (n - 1);
  // A value as bright as `peak` not drawn in n paths may still come with probability about
  // 1 / (n + 2) (Laplace's rule of succession): its share of a path's variance.
  if (peak > mean) variance += (peak - mean) * (peak - mean) / (n + 2);
  const double error = std::sqrt(variance / n);  // the standard error of the pixel's mean
  const float hi = static_cast<float>(exposure_scale * (mean + error));
  const float lo = static_cast<float>(exposure_scale * std::max(0.0, mean - error));
  return 0.5f * (DisplayValue(hi, filmic) - DisplayValue(lo, filmic)) <= threshold;
}

// What a tile's camera rays need, worked out once per tile.
struct PathTracer::Impl::CameraRays {
  const Camera& camera;
  const PixelRays& rays;
  const CameraMotion& motion;
  Eigen::Matrix3f rotation;  // world from camera
  Eigen::Vector3f origin;    // mm, world
  float aperture_radius;     // mm; 0: a pinhole
  float focus;               // mm
  float pixel_spread;        // a pixel's angular size: the camera rays' cone
  int u0, v0;                // the tile's top-left pixel
};

// A packet's 16 lanes: each a path of one of the tile's pixels, and what a bounce's shading
// passes hand on to each other.
struct PathTracer::Impl::Packet {
  int lanes = 0;  // lanes [0, lanes) carry paths; the others stay off
  // Lane j traces sample sample[j] of tile pixel pixel[j], whose stream is seed[j].
  int pixel[16], sample[16];
  uint64_t seed[16];

  // The paths: the current segments (Embree's layout) and which lanes still trace one, whether
  // the camera ray existed, and what each path carries and has gathered so far; the denoiser's
  // first-surface albedo and normal.
  RTCRayHit16 rh;
  alignas(64) int active[16];
  alignas(64) int had_ray[16];
  Eigen::Vector3f dir[16], throughput[16], value[16], first_albedo[16], first_normal[16];
  // The vertex the segment left: its BSDF sample's pdf and strategy selection probabilities (the
  // MIS weights of a light or a sampled sky the segment finds need them again), and the ray
  // cone's width there and spread since.
  float prev_pdf[16], cone_width[16], cone_spread[16];
  float selection[16][kMaxRated];
  // The smallest BSDF sampling density of the path's bounces so far (infinite before the first):
  // Filter Glossy widens the lobes the path meets after an unlikely bounce.
  float min_pdf[16];
  // The path's glossy bounces so far, and whether its segment is its last (more glossy bounces
  // than glossy_bounces: only the light and sky it finds count).
  int glossy[16];
  bool last_segment[16];

  // A bounce's shading, between its passes: the surface, its frame and BSDF, wo in that frame,
  // the offset origin (eps along the geometric normal), the light sample (its pdf times its
  // strategy's, and whether the light is a delta) and the two directions wi in the frame; their
  // BSDF values are entries nee_lane[j] and next_lane[j] of `evals` (-1: none).
  Surface surf[16];
  std::optional<ShadingFrame> frame[16];
  std::optional<PrincipledBsdf> bsdf[16];
  Eigen::Vector3f wo[16], p_off[16], nee_wi[16], next_wi[16];
  float eps[16];
  LightSample light_sample[16];
  float light_pdf[16];
  bool light_delta[16];
  int nee_lane[16], next_lane[16];
  bool next_glossy[16];  // a glossy lobe drew next_wi
  BsdfLanes evals;
  // The shadow rays and what each adds to its path's value if nothing blocks it.
  RTCRay16 shadow;
  alignas(64) int shadow_valid[16];
  Eigen::Vector3f shadow_value[16];
};

// Per pixel of a tile: the sums over its paths so far (radiance; the denoiser's first-surface
// albedo and normal; each path's luminance and its square, for the error estimate), the paths
// that had a ray, and the samples drawn (paths without a ray included).
struct PathTracer::Impl::PixelSums {
  Eigen::Vector3f sum[16], albedo[16], normal[16];
  double luminance[16] = {}, luminance_sq[16] = {}, luminance_max[16] = {};
  int paths[16] = {}, drawn[16] = {};

  PixelSums() {
    for (int p = 0; p < 16; ++p) {
      sum[p].setZero();
      albedo[p].setZero();
      normal[p].setZero();
    }
  }
  // Adds a traced packet's paths, in lane order.
  void Add(const Packet& k) {
    for (int j = 0; j < k.lanes; ++j) {
      const int p = k.pixel[j];
      ++drawn[p];
      if (!k.had_ray[j]) continue;  // a point of the pixel without a ray, beyond a lens's fold
      ++paths[p];
      sum[p] += k.value[j];
      albedo[p] += k.first_albedo[j];
      normal[p] += k.first_normal[j];
      const double l = Luminance(k.value[j]);
      luminance[p] += l;
      luminance_sq[p] += l * l;
      luminance_max[p] = std::max(luminance_max[p], l);
    }
  }
};

void PathTracer::Impl::TracePacket(const CameraRays& camera, Packet* k) const {
  RTCIntersectContext context;
  StartPaths(camera, k);
  rtcInitIntersectContext(&context);
  rtcIntersect16(k->active, scene.world, &context, &k->rh);
  for (int depth = 0; AddEmission(k, depth); ++depth) {
    SampleLanes(k, depth);
    EvaluateLanes(k);
    const bool more = ContinuePaths(k, depth);
    TraceShadows(k);
    if (!more) break;
    rtcInitIntersectContext(&context);
    rtcIntersect16(k->active, scene.world, &context, &k->rh);
  }
}

// Camera rays through a point of each lane's pixel: directions with camera z = 1, so that the
// clip range is in depth like the labels'.
void PathTracer::Impl::StartPaths(const CameraRays& c, Packet* k) const {
  for (int j = 0; j < 16; ++j) {
    k->active[j] = 0;
    k->value[j].setZero();
    k->first_albedo[j] = Eigen::Vector3f::Ones();
    k->first_normal[j].setZero();
    if (j >= k->lanes) {
      SetRayLane(&k->rh.ray, j, Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitZ(), 0, 0);
      k->had_ray[j] = 0;
      continue;
    }
    const int p = k->pixel[j];
    const int u = c.u0 + p % 4, v = c.v0 + p / 4;
    k->throughput[j].setOnes();
    k->prev_pdf[j] = 0;
    k->min_pdf[j] = kInf;
    k->glossy[j] = 0;
    k->last_segment[j] = false;
    k->cone_width[j] = 0;
    k->cone_spread[j] = c.pixel_spread;
    const PixelSampler sampler(k->seed[j], static_cast<uint32_t>(k->sample[j]));
    const Eigen::Vector2f jitter = sampler.Get2D(0);
    Eigen::Vector2f xy = Eigen::Vector2f::Zero();
    k->active[j] = c.rays.At(u, v, jitter.x(), jitter.y(), &xy) ? -1 : 0;
    k->had_ray[j] = k->active[j];
    Eigen::Vector3f o_cam = Eigen::Vector3f::Zero(), d_cam(xy.x(), xy.y(), 1.0f);
    if (c.aperture_radius > 0.0f) {
      // Through a point of the aperture to where the pixel's ray meets the plane of focus;
      // camera z of the direction stays 1.
      const Eigen::Vector2f l = ConcentricDisc(sampler.Get2D(kLensDimension)) * c.aperture_radius;
      o_cam = Eigen::Vector3f(l.x(), l.y(), 0.0f);
      d_cam -= o_cam / c.focus;
    }
    Eigen::Vector3f d = c.rotation * d_cam, o = c.origin + c.rotation * o_cam;
    if (c.motion.active()) {
      const Eigen::Isometry3d pose =
          c.camera.world_from_cam * c.motion.At(sampler.Get2D(kTimeDimension).x() - 0.5);
      const Eigen::Matrix3f r = pose.linear().cast<float>();
      d = r * d_cam;
      o = pose.translation().cast<float>() + r * o_cam;
    }
    k->dir[j] = d.normalized();
    SetRayLane(&k->rh.ray, j, o, d, scene.near_mm, scene.far_mm);
    k->rh.hit.geomID[j] = k->rh.hit.primID[j] = k->rh.hit.instID[0][j] = kInvalid;
  }
}

// Light reaching each lane's last vertex (or the camera) along its segment: area lights in front
// of the surface, and the sky if the ray escaped; lanes that escaped, or hit a surface beyond the
// last bounce, stop.
bool PathTracer::Impl::AddEmission(Packet* k, int depth) const {
  const bool shade = depth <= scene.bounces;
  const int num_lights = static_cast<int>(lights.size());
  bool any = false;
  for (int j = 0; j < 16; ++j) {
    if (!k->active[j]) continue;
    const RTCRayHit16& rh = k->rh;
    const bool hit = rh.hit.geomID[j] != kInvalid;
    const Eigen::Vector3f o(rh.ray.org_x[j], rh.ray.org_y[j], rh.ray.org_z[j]);
    // Camera rays are not unit length: their t is depth; compare along the unit direction.
    const float seg =
        hit ? rh.ray.tfar[j] *
                  (depth == 0
                       ? Eigen::Vector3f(rh.ray.dir_x[j], rh.ray.dir_y[j], rh.ray.dir_z[j]).norm()
                       : 1.0f)
            : kInf;
    const auto select_pdf = [&](int s) { return rated ? k->selection[j][s] : even_pdf; };
    for (int s = 0; s < num_lights; ++s) {
      Eigen::Vector3f le;
      float pdf;
      if (!HitLight(lights[s], o, k->dir[j], seg, &le, &pdf)) continue;
      const float w = depth == 0 ? 1.0f : PowerHeuristic(k->prev_pdf[j], select_pdf(s) * pdf);
      k->value[j] += ClampEmission(k->throughput[j].cwiseProduct(le) * w, depth);
    }
    if (!hit) {
      if (environment) {
        const Eigen::Vector3f le = environment->Eval(k->dir[j]);
        const float w = depth == 0 || !environment_sampled
                            ? 1.0f
                            : PowerHeuristic(k->prev_pdf[j],
                                             select_pdf(num_lights) * environment->Pdf(k->dir[j]));
        k->value[j] += ClampEmission(k->throughput[j].cwiseProduct(le) * w, depth);
      }
      k->active[j] = 0;
      continue;
    }
    if (!shade || k->last_segment[j]) {
      k->active[j] = 0;
      continue;
    }
    any = true;
  }
  return any;
}

// The first pass: each active lane's surface and BSDF, one light sample (next-event estimation:
// a strategy picked by SelectionPdfs, then a point of it) and the BSDF's sampled direction, both
// queued in `evals`.
void PathTracer::Impl::SampleLanes(Packet* k, int depth) const {
  BsdfLanes& evals = k->evals;
  evals.count = 0;
  for (int j = 0; j < 16; ++j) {
    k->shadow_valid[j] = 0;
    k->nee_lane[j] = k->next_lane[j] = -1;
    if (!k->active[j]) {
      SetRayLane(&k->shadow, j, Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitZ(), 0, 0);
      continue;
    }
    const Surface& surf = k->surf[j] =
        Hit(k->rh, j, k->dir[j], k->cone_width[j], k->cone_spread[j]);
    if (depth == 0) {
      k->first_albedo[j] = surf.params.base_color;
      k->first_normal[j] = surf.ns;
    }
    const ShadingFrame& local = k->frame[j].emplace(surf);
    const Eigen::Vector3f wo = local.ToLocal(-k->dir[j]);
    k->wo[j] = wo;
    // Filter Glossy (Cycles' formula): glossy lobes at least as wide as the path's least likely
    // bounce so far allows.
    float min_alpha = 0.0f;
    if (scene.filter_glossy > 0) {
      const float blur_pdf = k->min_pdf[j] / scene.filter_glossy;
      if (blur_pdf < 1.0f) min_alpha = 0.5f * std::sqrt(1.0f - blur_pdf);
    }
    const PrincipledBsdf& bsdf = k->bsdf[j].emplace(surf.params, min_alpha);
    const PixelSampler sampler(k->seed[j], static_cast<uint32_t>(k->sample[j]));
    // Two pairs a bounce: the light's (which light, then where on it) and the BSDF's (which
    // lobe, then which direction). Each picks with its x and reuses x rescaled into the picked
    // share (as Cycles does), so the samples one light or lobe gets keep the pair's
    // stratification instead of being a random subset of it.
    const uint32_t dim = 1 + 2 * static_cast<uint32_t>(depth);
    // A little off the surface along its geometric normal, scaled with the coordinates (float
    // spacing at 10 m is 1e-3 mm).
    k->eps[j] = 0.01f + 2e-6f * surf.p.cwiseAbs().maxCoeff();
    k->p_off[j] = surf.p + k->eps[j] * surf.ng;

    // Next-event estimation.
    SetRayLane(&k->shadow, j, k->p_off[j], Eigen::Vector3f::UnitZ(), 0, 0);
    if (num_strategies > 0) {
      int pick = 0;
      float select_pdf = even_pdf;
      Eigen::Vector2f u_light = sampler.Get2D(dim);
      float below = 0.0f;  // the picked strategy's share of [0, 1) starts here
      if (rated) {
        float* select = k->selection[j];
        SelectionPdfs({k->p_off[j], surf.ns, -k->dir[j], wo, &local.t, &local.b, &bsdf}, select);
        while (pick + 1 < num_strategies && u_light.x() >= below + select[pick]) {
          below += select[pick++];
        }
        select_pdf = select[pick];
      } else {
        pick = std::min(static_cast<int>(u_light.x() * num_strategies), num_strategies - 1);
        below = static_cast<float>(pick) * even_pdf;
      }
      u_light.x() = std::clamp((u_light.x() - below) / select_pdf, 0.0f, 0x1.fffffep-1f);
      LightSample& ls = k->light_sample[j];
      bool ok = false;
      k->light_delta[j] = false;
      if (pick < static_cast<int>(lights.size())) {
        ok = SampleLight(lights[pick], surf.p, u_light, &ls);
        k->light_delta[j] = lights[pick].delta;
      } else {
        ls.wi = environment->Sample(u_light, &ls.pdf);
        ls.distance = kInf;
        ls.value = environment->Eval(ls.wi);
        ok = ls.pdf > 0;
      }
      k->light_pdf[j] = select_pdf * ls.pdf;
      if (ok && ls.wi.dot(surf.ng) > 0) {
        const Eigen::Vector3f wi = local.ToLocal(ls.wi);
        if (wi.z() > 0) {
          k->nee_wi[j] = wi;
          k->nee_lane[j] = evals.count++;
          bsdf.ToLanes(wo, wi, &evals, k->nee_lane[j]);
        }
      }
    }

    // The BSDF's sample continues the path.
    if (const auto wi = bsdf.SampleDirection(wo, sampler.Get2D(dim + 1), &k->next_glossy[j])) {
      k->next_wi[j] = *wi;
      k->next_lane[j] = evals.count++;
      bsdf.ToLanes(wo, *wi, &evals, k->next_lane[j]);
    }
  }
}

// The second pass: the queued BSDF values and pdfs, all lanes at once in SIMD (EvalLanes), or
// one at a time with EvalWithPdf, the scalar reference (render.shading: scalar).
void PathTracer::Impl::EvaluateLanes(Packet* k) const {
  BsdfLanes& evals = k->evals;
  if (!scene.scalar_shading) {
    EvalLanes(&evals);
    return;
  }
  const auto eval = [&](int j, int i, const Eigen::Vector3f& wi) {
    const Eigen::Vector3f f = k->bsdf[j]->EvalWithPdf(k->wo[j], wi, &evals.pdf[i]);
    for (int c = 0; c < 3; ++c) evals.f[c][i] = f[c];
  };
  for (int j = 0; j < 16; ++j) {
    if (k->nee_lane[j] >= 0) eval(j, k->nee_lane[j], k->nee_wi[j]);
    if (k->next_lane[j] >= 0) eval(j, k->next_lane[j], k->next_wi[j]);
  }
}

// The third pass: each lane's light sample weighted by MIS becomes a shadow ray, and its BSDF
// sample the next segment (Russian roulette from the third interaction on).
bool PathTracer::Impl::ContinuePaths(Packet* k, int depth) const {
  const BsdfLanes& evals = k->evals;
  const auto lane_f = [&](int i) {
    return Eigen::Vector3f(evals.f[0][i], evals.f[1][i], evals.f[2][i]);
  };
  bool any = false;
  for (int j = 0; j < 16; ++j) {
    if (!k->active[j]) continue;
    if (const int i = k->nee_lane[j]; i >= 0) {
      const LightSample& ls = k->light_sample[j];
      const float w = k->light_delta[j] ? 1.0f : PowerHeuristic(k->light_pdf[j], evals.pdf[i]);
      Eigen::Vector3f c = k->throughput[j].cwiseProduct(lane_f(i)).cwiseProduct(ls.value) *
                          (k->nee_wi[j].z() * w / k->light_pdf[j]);
      if (depth >= 1) c = ClampIndirect(c);
      if (c.allFinite() && c.maxCoeff() > 0) {
        k->shadow_value[j] = c;
        k->shadow_valid[j] = -1;
        const float tfar = std::isinf(ls.distance) ? kInf : ls.distance * (1 - 1e-4f) - k->eps[j];
        SetRayLane(&k->shadow, j, k->p_off[j], ls.wi, 0, std::max(0.0f, tfar));
      }
    }

    k->active[j] = 0;
    const int i = k->next_lane[j];
    if (i < 0 || !(evals.pdf[i] > 0)) continue;
    const float pdf = evals.pdf[i];
    const Eigen::Vector3f weight = lane_f(i) * (k->next_wi[j].z() / pdf);
    const Surface& surf = k->surf[j];
    const ShadingFrame& local = *k->frame[j];
    const Eigen::Vector3f& w = k->next_wi[j];
    const Eigen::Vector3f wi = (w.x() * local.t + w.y() * local.b + w.z() * surf.ns).normalized();
    if (wi.dot(surf.ng) <= 0 || !weight.allFinite()) continue;
    Eigen::Vector3f next = k->throughput[j].cwiseProduct(weight);
    // Russian roulette from the third interaction on: continue with probability q.
    if (depth >= 2) {
      const float q = std::min(0.95f, next.maxCoeff());
      const float r = UnitFloat(static_cast<uint32_t>(Hash(
          k->seed[j], (static_cast<uint64_t>(k->sample[j]) << 8) | static_cast<uint64_t>(depth))));
      if (!(r < q)) continue;
      next /= q;
    }
    if (!(next.maxCoeff() > 0)) continue;
    k->throughput[j] = next;
    k->prev_pdf[j] = pdf;
    k->min_pdf[j] = std::min(k->min_pdf[j], pdf);
    // The cone widens by the lobe it was drawn from: about alpha for a glossy reflection, a
    // radian for a diffuse one.
    k->cone_width[j] = surf.cone_width;
    k->cone_spread[j] += pdf > 1 ? std::sqrt(k->bsdf[j]->alpha_x() * k->bsdf[j]->alpha_y()) : 1.0f;
    k->dir[j] = wi;
    k->glossy[j] += k->next_glossy[j] ? 1 : 0;
    k->last_segment[j] = k->glossy[j] > scene.glossy_bounces;
    k->active[j] = -1;
    any = true;
    SetRayLane(&k->rh.ray, j, k->p_off[j], wi, 0, kInf);
    k->rh.hit.geomID[j] = k->rh.hit.primID[j] = k->rh.hit.instID[0][j] = kInvalid;
  }
  return any;
}

// The shadow rays: each unblocked one adds its light to its path.
void PathTracer::Impl::TraceShadows(Packet* k) const {
  bool any = false;
  for (int j = 0; j < 16; ++j) any |= k->shadow_valid[j] != 0;
  if (!any) return;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcOccluded16(k->shadow_valid, scene.world, &context, &k->shadow);
  for (int j = 0; j < 16; ++j) {
    if (k->shadow_valid[j] && k->shadow.tfar[j] >= 0) k->value[j] += k->shadow_value[j];
  }
}

void PathTracer::TraceTile(const Camera& camera, const PixelRays& rays, const ThinLens& lens,
                           const CameraMotion& motion, int u0, int v0,
                           const AdaptiveSampling& sampling, uint64_t frame_seed,
                           Eigen::Vector3f out[16], TileFeatures* features, int taken[16]) const {
  const Impl& im = *impl_;
  const Intrinsics& intrinsics = camera.intrinsics;
  const Impl::CameraRays camera_rays{
      camera,
      rays,
      motion,
      camera.world_from_cam.linear().cast<float>(),
      camera.world_from_cam.translation().cast<float>(),
      lens.active() ? static_cast<float>(0.5 * lens.aperture_mm()) : 0.0f,
      static_cast<float>(lens.focus_distance_mm),
      static_cast<float>(1.0 / std::min(intrinsics.fx, intrinsics.fy)),
      u0,
      v0};
  const int samples = sampling.samples;
  uint64_t pixel_seed[16];
  bool in_image[16];
  for (int p = 0; p < 16; ++p) {
    const int u = u0 + p % 4, v = v0 + p / 4;
    in_image[p] = u < intrinsics.width && v < intrinsics.height;
    pixel_seed[p] = Hash(frame_seed, static_cast<uint64_t>(v) * 65536u + static_cast<uint64_t>(u));
  }
  Impl::PixelSums sums;
  Impl::Packet packet;

  // Runs `count[p]` more samples of each tile pixel p, 16 paths per packet: sample by sample,
  // pixel by pixel within a sample (so a whole tile's first packets are one sample of each pixel).
  const auto run = [&](const int count[16]) {
    const auto trace = [&] {
      im.TracePacket(camera_rays, &packet);
      sums.Add(packet);
      packet.lanes = 0;
    };
    int most = 0, base[16];
    for (int p = 0; p < 16; ++p) most = std::max(most, count[p]), base[p] = sums.drawn[p];
    packet.lanes = 0;
    for (int i = 0; i < most; ++i) {
      for (int p = 0; p < 16; ++p) {
        if (i >= count[p]) continue;
        const int j = packet.lanes++;
        packet.pixel[j] = p;
        packet.sample[j] = base[p] + i;
        packet.seed[j] = pixel_seed[p];
        if (packet.lanes == 16) trace();
      }
    }
    if (packet.lanes > 0) trace();
  };

  int count[16];
  const int first = sampling.adaptive() ? std::min(samples, sampling.min_samples) : samples;
  for (int p = 0; p < 16; ++p) count[p] = in_image[p] ? first : 0;
  run(count);
  while (sampling.adaptive()) {
    // A pixel goes on while its own estimate or a 4-neighbour's in the tile is above the
    // threshold (Cycles' dilation of unconverged pixels), until it has `samples`.
    bool converged[16];
    for (int p = 0; p < 16; ++p) {
      if (!in_image[p]) {
        converged[p] = true;
        continue;
      }
      // The brightest path of the pixel and its 8 neighbours in the tile: a highlight the
      // pixel's own paths have not found yet (a rough metal part's, a small sub-pixel one)
      // shows in its neighbours' paths first. (Pixels outside the image have no paths: 0.)
      const int x = p % 4, y = p / 4;
      double peak = 0.0;
      for (int dy = std::max(0, y - 1); dy <= std::min(3, y + 1); ++dy) {
        for (int dx = std::max(0, x - 1); dx <= std::min(3, x + 1); ++dx) {
          peak = std::max(peak, sums.luminance_max[dy * 4 + dx]);
        }
      }
      converged[p] =
          sampling.Converged(sums.paths[p], sums.luminance[p], sums.luminance_sq[p], peak);
    }
    int open = 0;
    for (int p = 0; p < 16; ++p) {
      const int x = p % 4, y = p / 4;
      const bool near_open = !converged[p] || (x > 0 && !converged[p - 1]) ||
                             (x < 3 && !converged[p + 1]) || (y > 0 && !converged[p - 4]) ||
                             (y < 3 && !converged[p + 4]);
      count[p] = in_image[p] && near_open && sums.drawn[p] < samples ? 1 : 0;
      open += count[p];
    }
    if (open == 0) break;
    // Steps that fill packets: 16 paths over the open pixels, at least a quarter of what each
    // has drawn (a geometric schedule, so the checks cost little), within `samples`.
    for (int p = 0; p < 16; ++p) {
      if (count[p] == 0) continue;
      const int step = std::max((16 + open - 1) / open, sums.drawn[p] / 4);
      count[p] = std::min(step, samples - sums.drawn[p]);
    }
    run(count);
  }

  for (int p = 0; features != nullptr && p < 16; ++p) {
    const int n = sums.paths[p];
    features->albedo[p] = n > 0 ? Eigen::Vector3f(sums.albedo[p] / n) : Eigen::Vector3f::Ones();
    features->normal[p] = n > 0 ? Eigen::Vector3f(sums.normal[p] / n) : Eigen::Vector3f::Zero();
    // The variance of the mean; one path says nothing of its spread: as much as its value.
    const double mean = n > 0 ? sums.luminance[p] / n : 0.0;
    features->variance[p] =
        n > 1 ? static_cast<float>(std::max(0.0, sums.luminance_sq[p] - n * mean * mean) / (n - 1) /
                                   n)
              : static_cast<float>(mean * mean);
  }
  // (Paths from points of the pixel without a ray, beyond a lens's fold, are left out.)
  for (int p = 0; p < 16; ++p) {
    out[p] = in_image[p] && sums.paths[p] > 0 ? Eigen::Vector3f(sums.sum[p] / sums.paths[p])
                                              : Eigen::Vector3f::Zero();
    if (taken != nullptr) taken[p] = in_image[p] ? sums.drawn[p] : 0;
  }
}

}  // namespace cadsynth
