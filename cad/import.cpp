#include "cad/import.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESCAFControl_Reader.hxx>
#include <IGESData_IGESModel.hxx>
#include <Standard_Failure.hxx>
#include <TCollection_HAsciiString.hxx>
#include <TDocStd_Document.hxx>
#include <TopoDS_Shape.hxx>
#include <XCAFApp_Application.hxx>

#include "cad/assembly.h"
#include "cad/core/error.h"
#include "cad/core/units.h"
#include "cad/occt_shape.h"
#include "cad/step.h"
#include "cad/xde.h"

namespace cadsynth {

bool ImportOptions::Check(std::string* why) const {
  if (!tessellation.Check(why)) return false;
  if (!unit.empty() && !LengthUnitMm(unit)) {
    *why = "unknown length unit '" + unit + "' (use um, mm, cm, m, in or ft)";
    return false;
  }
  if (!encoding.empty() && StepCodePage(encoding).empty()) {
    *why =
        "unknown encoding '" + encoding + "' (e.g. utf-8, cp1251, cp1252, sjis, gb2312, iso8859-5)";
    return false;
  }
  if (!(crease_angle_rad >= 0.0) || crease_angle_rad > M_PI) {
    *why = "crease_angle must be between 0 and 180 degrees";
    return false;
  }
  return true;
}

CadFormat DetectFormat(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".step" || ext == ".stp" || ext == ".p21") return CadFormat::kStep;
  if (ext == ".iges" || ext == ".igs") return CadFormat::kIges;
  if (ext == ".brep" || ext == ".rle") return CadFormat::kBrep;
  for (const char* mesh : {".stl", ".obj", ".ply", ".dae", ".gltf", ".glb", ".3mf", ".off"}) {
    if (ext == mesh) return CadFormat::kMesh;
  }
  internal::RequireReadableFile(path.string());
  std::ifstream in(path, std::ios::binary);
  std::string head(256, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  if (head.find("ISO-10303-21") != std::string::npos) return CadFormat::kStep;
  if (head.find("CASCADE Topology") != std::string::npos ||
      head.find("DBRep_DrawableShape") != std::string::npos) {
    return CadFormat::kBrep;
  }
  throw Error(path.string() +
              ": unknown kind of file (expected STEP .step/.stp, IGES .iges/.igs, OpenCASCADE "
              ".brep, or a mesh .stl/.obj/.ply/.dae/.gltf/.glb/.3mf/.off)");
}

void ScaleAssembly(Assembly* assembly, double factor) {
  if (factor == 1.0) return;
  const float f = static_cast<float>(factor);
  for (Part& part : assembly->parts) {
    if (!part.brep.IsNull()) part.brep = Scaled(part.brep, Eigen::Vector3d::Constant(factor));
    for (Eigen::Vector3f& p : part.mesh.positions) p *= f;
    part.cad_from_model.translation() *= factor;
    part.mass.volume_mm3 *= factor * factor * factor;
    part.mass.center_of_mass *= factor;
    part.mass.inertia *= std::pow(factor, 5);
    for (Eigen::Isometry3d& s : part.symmetries.discrete) s.translation() *= factor;
    for (Symmetries::Axis& a : part.symmetries.continuous) a.offset *= factor;
  }
  for (Instance& instance : assembly->instances) instance.world_from_model.translation() *= factor;
}

Assembly ReadIges(const std::filesystem::path& path, const TessellationOptions& options) {
  const std::string file = path.string();
  internal::RequireReadableFile(file);
  internal::InitOcct();
  internal::CadContents contents;
  std::string length_unit;
  {
    std::lock_guard<std::mutex> lock(internal::XdeMutex());
    try {
      internal::DocumentGuard document;
      IGESCAFControl_Reader reader;
      reader.SetNameMode(true);
      reader.SetColorMode(true);
      const std::string absolute = std::filesystem::absolute(path).lexically_normal().string();
      if (reader.ReadFile(absolute.c_str()) != IFSelect_RetDone) {
        throw Error(file + ": not a readable IGES file (OpenCASCADE could not parse it)");
      }
      const Handle(IGESData_IGESModel) model = Handle(IGESData_IGESModel)::DownCast(reader.Model());
      if (!model.IsNull() && !model->GlobalSection().UnitName().IsNull()) {
        length_unit = model->GlobalSection().UnitName()->ToCString();
      }
      if (!reader.Transfer(document.doc)) {
        throw Error(file + ": OpenCASCADE could not translate the IGES entities");
      }
      contents = internal::CollectDocument(document.doc, file);
    } catch (const Standard_Failure& failure) {
      throw Error(file + ": cannot read: " + internal::PlainFailure(failure));
    }
  }
  Assembly assembly = internal::BuildAssembly(file, std::move(contents), options);
  assembly.format = "IGES";
  assembly.length_unit = length_unit;
  return assembly;
}

namespace {

// An ASCII BREP file cut short inside its shape list made OpenCASCADE's reader loop for ever.
// The list ("TShapes N") holds N records, each ending in its sub-shape list and a "*" line, and
// the root shape's reference follows them: a file that lacks any of this is refused first.
void CheckBrepComplete(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  long declared = -1, complete = 0;
  bool root = false;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (declared < 0) {
      if (line.rfind("TShapes ", 0) == 0) {
        declared = std::strtol(line.c_str() + 8, nullptr, 10);
        if (declared < 0) declared = 0;
      }
      continue;
    }
    const size_t last = line.find_last_not_of(' ');
    if (complete < declared) {
      if (last != std::string::npos && line[last] == '*') ++complete;
    } else if (last != std::string::npos) {
      root = true;
      break;
    }
  }
  if (declared < 0) return;  // binary, or no shape list: OpenCASCADE says what is wrong
  if (complete < declared || !root) {
    throw Error(path.string() + ": truncated: the file declares " + std::to_string(declared) +
                " shapes and ends " +
                (complete < declared ? "after " + std::to_string(complete) + " of them"
                                     : "before naming its root shape"));
  }
}

}  // namespace

Assembly ReadBrep(const std::filesystem::path& path, const TessellationOptions& options) {
  const std::string file = path.string();
  internal::RequireReadableFile(file);
  CheckBrepComplete(path);
  internal::InitOcct();
  TopoDS_Shape shape;
  try {
    BRep_Builder builder;
    if (!BRepTools::Read(shape, file.c_str(), builder) || shape.IsNull()) {
      throw Error(file + ": not a readable OpenCASCADE BREP file (damaged or cut short?)");
    }
  } catch (const Standard_Failure& failure) {
    throw Error(file +
                ": not a readable OpenCASCADE BREP file: " + internal::PlainFailure(failure));
  }
  internal::CadContents contents;
  contents.name = path.stem().string();
  contents.part_names = {contents.name};
  contents.part_shapes = {WrapShape(shape)};
  contents.part_colors = {std::nullopt};
  contents.instances = {Instance{0, contents.name, Eigen::Isometry3d::Identity()}};
  Assembly assembly = internal::BuildAssembly(file, std::move(contents), options);
  assembly.format = "BREP";
  return assembly;
}

namespace {

// The unit among common ones that would make the largest extent closest to 100 mm.
std::string LikelyUnit(double extent_in_file_units) {
  std::string best = "mm";
  double best_score = 1e300;
  for (const char* unit : {"um", "mm", "cm", "m", "in"}) {
    const double score = std::abs(std::log10(extent_in_file_units * *LengthUnitMm(unit) / 100.0));
    if (score < best_score) {
      best_score = score;
      best = unit;
    }
  }
  return best;
}

}  // namespace

Assembly ImportCad(const std::filesystem::path& path, const ImportOptions& options) {
  const std::string file = path.string();
  std::string why;
  if (!options.Check(&why)) throw Error(file + ": " + why);
  const CadFormat format = DetectFormat(path);
  Assembly assembly;
  switch (format) {
    case CadFormat::kStep:
      assembly = ReadStep(path, options.tessellation, options.encoding);
      break;
    case CadFormat::kIges:
      assembly = ReadIges(path, options.tessellation);
      break;
    case CadFormat::kBrep:
      assembly = ReadBrep(path, options.tessellation);
      break;
    case CadFormat::kMesh:
      assembly = ReadMesh(path, options.crease_angle_rad);
      break;
  }

  // A NaN or infinite coordinate poisons everything after (hulls, bounds, the tracer).
  for (const Part& part : assembly.parts) {
    for (size_t v = 0; v < part.mesh.positions.size(); ++v) {
      if (!part.mesh.positions[v].allFinite()) {
        throw Error(file + ": part '" + part.name + "': vertex " + std::to_string(v) +
                    " is not a finite number");
      }
    }
  }
  if (options.crease_angle_rad == 0.0) {
    for (Part& part : assembly.parts) part.mesh.MakeFaceted();
  }
  // Files that store N copies of one shape; meshes of one surface lie within twice the deflection.
  MergeIdenticalParts(&assembly, 2.0 * options.tessellation.linear_deflection_mm + 1e-3);

  // What one unit of the file's numbers is in mm, and what the translator already assumed.
  double assumed_mm = 1.0;
  // STEP and IGES declare a unit, and so do COLLADA (its header) and glTF (metres).
  const bool declares_unit = format == CadFormat::kStep || format == CadFormat::kIges ||
                             (format == CadFormat::kMesh && !assembly.length_unit.empty());
  if (declares_unit && !assembly.length_unit.empty()) {
    const std::optional<double> declared = LengthUnitMm(assembly.length_unit);
    if (declared) assumed_mm = *declared;
  }
  if (!options.unit.empty()) {
    if (declares_unit && !assembly.length_unit.empty() && !LengthUnitMm(assembly.length_unit)) {
      throw Error(file + ": cannot override the unit: the file's unit '" + assembly.length_unit +
                  "' is not one cadsynth knows");
    }
    const double stated_mm = *LengthUnitMm(options.unit);
    ScaleAssembly(&assembly, stated_mm / assumed_mm);
    assembly.length_unit =
        options.unit + " (stated by the recipe" +
        (assembly.length_unit.empty() ? std::string(")")
                                      : ", file declares " + assembly.length_unit + ")");
    assumed_mm = stated_mm;
  } else if (!declares_unit) {
    assembly.length_unit = "none (taken as mm)";
  }

  // A part over 5 m or under 1 mm is most likely in another unit than assumed.
  double largest = 0.0;
  for (const Part& part : assembly.parts)
    largest = std::max(largest, part.mesh.Bounds().sizes().maxCoeff());
  if (largest > 5000.0 || largest < 1.0) {
    std::ostringstream message;
    message.precision(4);
    const double in_file_units = largest / assumed_mm;
    const std::string likely = LikelyUnit(in_file_units);
    message << file << ": largest part is " << largest;
    // Past a kilometre nothing renders sensibly (and ray tracing loses its precision): an error.
    const bool refused = largest > kMaxPartSizeMm;
    message << (refused ? " mm, more than the 1 km cadsynth takes" : " mm, implausible for a part")
            << "; if the file's numbers are in " << likely << ", state `unit: " << likely
            << "` (it would then be " << in_file_units * *LengthUnitMm(likely) << " mm)";
    if (refused) throw Error(message.str());
    Warn(message.str());
  }
  return assembly;
}

}  // namespace cadsynth
