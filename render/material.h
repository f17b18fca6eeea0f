// Materials of the physically based mode: a Principled surface (render/bsdf.h, with an optional
// clear coat), named presets for industrial parts, and textures that need no downloads
// (procedural) or come from image files.
//
// Procedural textures are solid: they are functions of the 3D point (the part's model frame, so
// they stick to the part; the world for the floor), which needs no UVs and leaves no seams. Image
// textures follow a mesh's own texture coordinates where it has them (OBJ, glTF and other files
// assimp reads) and are projected triplanarly otherwise (three axis-aligned projections blended by
// the normal), as CAD meshes have no UVs. Textures modulate the base colour, the roughness and the
// normal (bump).
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "cad/core/schema.h"
#include "render/bsdf.h"
#include "render/image.h"

namespace cadsynth {

struct Texture {
  enum class Kind {
    kNone,
    kNoise,      // fractal value noise: mottled colour and roughness
    kBrushed,    // fine streaks along the model x axis (brushed or ground metal)
    kTurned,     // fine rings about the model z axis (lathe-turned faces)
    kChecker,    // a 3D checkerboard of `color` and the base colour, cells of `scale`
    kConcrete,   // speckled, blotchy grey: noise at several scales and pits
    kWood,       // growth rings about the y axis, distorted by noise
    kRust,       // `color` (rust by default) blended in where a noise mask exceeds 1 - `amount`
    kScratches,  // thin straight scratches, about `amount` of them per cell of `scale`: brighter
                 // and smoother along them (handling marks on machined metal)
    kImage,  // an image file (PNG, JPEG, EXR): by the mesh's UVs, or triplanar in tiles of `scale`
  };
  // How an image texture meets the surface. kAuto: the mesh's texture coordinates where it has
  // them, triplanar otherwise; kTriplanar always; kUv only on meshes with texture coordinates.
  enum class Projection { kAuto, kTriplanar, kUv };
  Kind kind = Kind::kNone;
  Projection projection = Projection::kAuto;
  double scale_mm = 20.0;  // feature size: noise cell, streak length, checker cell, image tile
  float amount = 0.3f;     // [0, 1]: how strongly the colour is changed (rust: covered fraction)
  float roughness_amount = 0.2f;               // [0, 1]: roughness varies by up to this much
  float bump = 0.0f;                           // [0, 1]: normal perturbation (0: flat)
  Eigen::Vector3f color{0.35f, 0.12f, 0.04f};  // second colour (checker, rust, wood), linear
  uint64_t seed = 0;                           // pattern variant
  std::filesystem::path image;                 // kImage
  std::shared_ptr<const LinearImage> pixels;   // kImage: the file's pixels, once read

  // In the recipe's order; `type` (a new type starts from its defaults), `seed` (a negative one
  // wraps) and `projection` (its own message) are read by hand.
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.kind, Field{.key = "type",
                        .kind = "choice",
                        .doc = "the pattern",
                        .choices = {"none", "noise", "brushed", "turned", "checker", "concrete",
                                    "wood", "rust", "scratches", "image"},
                        .by_hand = true});
    visit(o.scale_mm, Field{.key = "scale",
                            .kind = "length",
                            .doc = "the pattern's size",
                            .range = Range::kPositive});
    visit(o.amount, UnitNumber("amount", "how strongly it changes the colour (0-1)"));
    visit(o.roughness_amount,
          UnitNumber("roughness", "how strongly it changes the roughness (0-1)"));
    visit(o.bump, UnitNumber("bump", "how strongly it bumps the normal (0-1)"));
    visit(o.color, Field{"color", "linear_color", "the pattern's second colour"});
    visit(o.seed,
          Field{.key = "seed", .kind = "integer", .doc = "the pattern's seed", .by_hand = true});
    visit(o.image, Field{.key = "file",
                         .kind = "path",
                         .doc = "the image (PNG, JPEG, EXR, HDR)",
                         .only_with = {"image"}});
    visit(o.projection, Field{.key = "projection",
                              .kind = "choice",
                              .doc = "how the image is laid on the part",
                              .choices = {"auto", "triplanar", "uv"},
                              .by_hand = true,
                              .only_with = {"image"}});
  }
};

struct Material {
  PrincipledParams surface;
  Texture texture;
  // The base colour comes from the part's CAD colour (or the palette) rather than `surface`:
  // presets of paints and plastics do, metals do not (their colour is the metal's).
  bool base_from_part = false;
  // The direction anisotropic highlights stretch along (the BSDF's tangent). kRadial is Blender's
  // default when a Principled BSDF's Tangent is not connected: around the object's z axis through
  // the centre of its bounding box, in box-normalised coordinates (Cycles' tangent from Generated
  // coordinates), so a turned part shines in rings; kModelX runs along the model's x axis (the
  // `brushed` texture's streaks; the presets stainless and aluminium).
  enum class Tangent { kRadial, kModelX };
  Tangent tangent = Tangent::kRadial;

  bool Check(std::string* why) const;

  // The material's own fields; `surface` and `texture` describe theirs (PrincipledParams::Fields,
  // Texture::Fields).
  template <class Self, class Visit>
  static void Fields(Self& o, Visit&& visit) {
    visit(o.tangent,
          Field{"tangent",
                "choice",
                "where anisotropic highlights stretch: Blender's radial default or the model's x",
                {"radial", "x"}});
    visit(o.base_from_part, Field{.kind = "bool",
                                  .doc = "the base colour is the part's own (base_color: cad)",
                                  .internal_name = "base_from_part"});
  }
};

// The presets, linear base colours from measured reflectances of the metals (F0) and typical
// roughness of machined or moulded surfaces: steel, stainless (brushed), aluminium, brass,
// cast_iron, black_oxide, painted, abs, nylon, rubber, and for floors and tables: concrete, wood,
// plastic_sheet, rubber_mat. False for an unknown name.
bool MaterialPreset(const std::string& name, Material* material);
std::vector<std::string> MaterialPresetNames();

// What a texture does at one point: multiply the base colour, add to the roughness, tilt the
// normal (a vector in the tangent plane to add to the unit normal before normalising).
struct TextureSample {
  Eigen::Vector3f color_scale = Eigen::Vector3f::Ones();
  Eigen::Vector3f color_mix = Eigen::Vector3f::Zero();  // blended in by `mix`
  float mix = 0.0f;
  // Whether what `mix` blends in is a coating that is not metal (rust, paint, wood: the metallic
  // weight falls with `mix`) or only the base colour (an image: metallic stays, as with an image
  // on Blender's Base Color input).
  bool mix_is_coating = true;
  float roughness_offset = 0.0f;
  Eigen::Vector3f normal_offset = Eigen::Vector3f::Zero();
};

// Evaluates `texture` at point `p` (mm) with unit normal `n`, both in the texture's frame.
// `image` is the loaded image for kImage (else ignored). `footprint_mm` is the size of the patch
// of surface the sample stands for (a pixel's, or a wider one after rough bounces): noise octaves
// finer than it are replaced by their mean, which is what they average to over the patch (a
// filtered texture, cheaper too); 0 evaluates every octave. `uv`, when given, is the surface's
// texture coordinate (OpenGL convention: v up from the image's bottom row): an image texture
// whose projection allows it then reads the image there instead of projecting it.
TextureSample EvalTexture(const Texture& texture, const Eigen::Vector3f& p,
                          const Eigen::Vector3f& n, const LinearImage* image,
                          float footprint_mm = 0.0f, const Eigen::Vector2f* uv = nullptr);

// Applies a texture sample to a surface: the modulated parameters, clamped to their ranges.
PrincipledParams ApplyTexture(const PrincipledParams& surface, const TextureSample& sample);

// 3D value noise in [0, 1], smooth (C2), period-free; `seed` picks the pattern. The value at a
// lattice point (x, y, z) (integers, 32-bit wrap-around) is the top 24 bits of Wellons' lowbias32
// of s ^ 0x8DA6B343 x ^ 0xD8163841 y ^ 0xCB1AB31F z over 2^24, s = the low word of
// seed ^ (seed >> 32); between lattice points, trilinear in the quintic fade of each coordinate's
// fraction (x first, then y, then z).
float ValueNoise(const Eigen::Vector3f& p, uint64_t seed);
// Fractal sum of `octaves` value noises, each twice the frequency and half the amplitude, in
// [0, 1]. Octaves whose cells (1, 1/2, 1/4, ... in p's units) are smaller than `footprint` (same
// units) count as their mean, 1/2. Octave o is ValueNoise(q_o, Hash(seed, o)) with q_0 = p and
// q_(o+1) = (1.6 x + 1.2 y, -1.2 x + 1.6 y, 2 z) of q_o (turned so that lattices do not line
// up), weighted 2^-(o+1) and summed in order; four octaves are evaluated at once (SIMD).
float FractalNoise(const Eigen::Vector3f& p, int octaves, uint64_t seed, float footprint = 0.0f);

}  // namespace cadsynth
