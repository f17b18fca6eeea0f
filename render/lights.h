// Lights of the physically based mode, in Blender's units so that numbers from a Blender or
// BlenderProc scene carry over (positions and sizes in mm, like everything in cadsynth):
//
//   point  power P (W) spread evenly over all directions: intensity I = P / (4 pi) W/sr. With a
//          radius r it is a sphere of radiance P / (4 pi^2 r^2) (soft shadows, same intensity).
//   spot   a point light masked to a cone: same intensity as the point light of the same power
//          inside the cone (Blender: the cone does not concentrate the power), a smooth edge of
//          width `blend` (smoothstep over (1 - cos(size / 2)) blend of the cosine).
//   rect,  one-sided area lights facing `direction`, radiance L = P / (4 A) over their area A, as
//   disc   Cycles has it (0.25 / area): a Lambertian emitter of pi P / 4 watts, Blender's "W" for
//          area lights (a physical P watts would be P / (pi A), 4 / pi = 1.27x brighter).
//   sun    irradiance E (W/m^2) on a surface facing it; a disc of angular diameter `angle` on the
//          sky of radiance E / (pi sin^2(angle / 2)) (0: a perfectly parallel light).
//   environment  radiance colour * strength from every direction (Blender's world colour and
//          strength), or a procedural sky, or an equirectangular HDR/EXR image times strength.
//
// Radiance is in W/(m^2 sr); the rendered linear value of a pixel is the radiance it sees (before
// exposure), as in Blender. 1 mm = 1e-3 m enters wherever a length meets a power.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "cad/core/schema.h"
#include "render/image.h"

namespace cadsynth {

struct LightSource {
  enum class Kind { kPoint, kSpot, kRect, kDisc, kSun };
  Kind kind = Kind::kPoint;
  Eigen::Vector3f color = Eigen::Vector3f::Ones();  // linear RGB in [0, 1], scales the power
  // W for point, spot, rect and disc (Blender's Power); W/m^2 for the sun (Blender's Strength).
  double power = 1000.0;
  Eigen::Vector3d position{0.0, 0.0, 2000.0};  // mm, world (not used by the sun)
  // Where the light points (world, any length): the spot's axis, the side an area light shines
  // to, the way the sun's rays travel.
  Eigen::Vector3d direction{0.0, 0.0, -1.0};
  double radius_mm = 0.0;  // point, spot: radius of the emitting sphere (0: a point); disc: radius
  double size_x_mm = 500.0, size_y_mm = 500.0;  // rect: side lengths
  // rect: the direction of its x side (projected onto its plane; world x, or y if x is its axis).
  Eigen::Vector3d x_axis{1.0, 0.0, 0.0};
  double spot_size_rad = 0.7853981633974483;  // spot: full cone angle (Blender's default 45 deg)
  double spot_blend = 0.15;                   // spot: [0, 1], softness of the cone's edge
  double angle_rad = 0.00918043;              // sun: angular diameter (0.526 deg, Blender's)

  bool Check(std::string* why) const;

  // In the recipe's order. Read by hand: `type` (the tag the other keys go with), the power (a
  // sun's is `strength`), the direction (or a `target`) and the size (`size`: a length or [x, y]).
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.kind, Field{.key = "type",
                        .kind = "choice",
                        .doc = "the kind of light",
                        .choices = {"point", "spot", "rect", "disc", "sun"},
                        .by_hand = true});
    visit(o.color, Field{"color", "linear_color", "its colour"});
    visit(o.position, Field{.key = "position",
                            .kind = "length3",
                            .doc = "where it is",
                            .only_with = {"point", "spot", "rect", "disc"}});
    visit(o.power, Field{.key = "power",
                         .kind = "number",
                         .doc = "W, as Blender's",
                         .by_hand = true,
                         .range = Range::kNonNegative,
                         .only_with = {"point", "spot", "rect", "disc"}});
    visit(o.radius_mm, Field{.key = "radius",
                             .kind = "length",
                             .doc = "its radius (soft shadows)",
                             .range = Range::kNonNegative,
                             .only_with = {"point", "spot", "disc"}});
    visit(o.direction, Field{.key = "direction",
                             .kind = "vector3",
                             .doc = "the way it shines",
                             .by_hand = true,
                             .only_with = {"spot", "rect", "disc", "sun"}});
    visit(o.spot_size_rad, Field{.key = "spot_size",
                                 .kind = "angle",
                                 .doc = "the cone's full angle",
                                 .only_with = {"spot"}});
    visit(o.spot_blend, Field{.key = "spot_blend",
                              .kind = "number",
                              .doc = "the cone edge's softness (0-1)",
                              .only_with = {"spot"}});
    visit(o.size_x_mm,
          Field{.kind = "length", .doc = "rect: its x side", .internal_name = "size_x"});
    visit(o.size_y_mm,
          Field{.kind = "length", .doc = "rect: its y side", .internal_name = "size_y"});
    visit(o.x_axis, Field{.key = "x_axis",
                          .kind = "vector3",
                          .doc = "the rectangle's x direction",
                          .only_with = {"rect"}});
    visit(o.angle_rad, Field{.key = "angle",
                             .kind = "angle",
                             .doc = "the sun's angular diameter",
                             .only_with = {"sun"}});
  }
};

struct Environment {
  enum class Kind { kUniform, kSky, kImage };
  Kind kind = Kind::kUniform;
  float strength = 1.0f;
  Eigen::Vector3f color{0.05f, 0.05f, 0.05f};  // uniform (Blender's default world grey)
  // sky: radiance blends from `horizon` at the horizon to `zenith` overhead (by the sine of the
  // elevation, squared-root shaped), and is `ground` below the horizon.
  Eigen::Vector3f zenith{0.20f, 0.35f, 0.65f}, horizon{0.75f, 0.80f, 0.85f},
      ground{0.25f, 0.23f, 0.21f};
  // image: an equirectangular (latitude-longitude) HDR, EXR or 8-bit image, linear RGB (8-bit
  // images are decoded from sRGB). Blender's mapping, z up: the image's centre column looks along
  // +x, u = 0.5 - atan2(y, x) / (2 pi), its top row is the zenith. `rotation` turns it about z.
  std::filesystem::path image;
  std::shared_ptr<const LinearImage> pixels;  // the image's pixels, once read
  double rotation_rad = 0.0;

  bool Check(std::string* why) const;

  // `type` (the tag the other keys go with) is read by hand, and so are the file's pixels.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.kind, Field{.key = "type",
                        .kind = "choice",
                        .doc = "the kind of world",
                        .choices = {"uniform", "sky", "image"},
                        .by_hand = true});
    visit(
        o.color,
        Field{
            .key = "color", .kind = "linear_color", .doc = "its colour", .only_with = {"uniform"}});
    visit(o.strength, Field{.key = "strength",
                            .kind = "number",
                            .doc = "a factor on its radiance",
                            .range = Range::kNonNegative});
    visit(o.zenith, Field{.key = "zenith",
                          .kind = "linear_color",
                          .doc = "the sky's colour overhead",
                          .only_with = {"sky"}});
    visit(o.horizon, Field{.key = "horizon",
                           .kind = "linear_color",
                           .doc = "at the horizon",
                           .only_with = {"sky"}});
    visit(o.ground, Field{.key = "ground",
                          .kind = "linear_color",
                          .doc = "below the horizon",
                          .only_with = {"sky"}});
    visit(o.image, Field{.key = "file",
                         .kind = "path",
                         .doc = "an equirectangular HDR or EXR image",
                         .only_with = {"image"}});
    visit(o.rotation_rad, Field{.key = "rotation",
                                .kind = "angle",
                                .doc = "about the vertical, as a Mapping node's z",
                                .only_with = {"image"}});
  }
};

}  // namespace cadsynth
