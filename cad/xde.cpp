#include "cad/xde.h"

#include <algorithm>
#include <array>
#include <filesystem>
#include <map>
#include <system_error>

#include <tbb/parallel_for.h>
#include <BRepGProp.hxx>
#include <GProp_GProps.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_Printer.hxx>
#include <Quantity_Color.hxx>
#include <Standard_Failure.hxx>
#include <TCollection_AsciiString.hxx>
#include <TDF_Label.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDF_Tool.hxx>
#include <TDataStd_Name.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <gp_Trsf.hxx>

#include "cad/core/error.h"
#include "cad/mesh_analysis.h"
#include "cad/occt_shape.h"

namespace cadsynth::internal {
namespace {

std::string LabelName(const TDF_Label& label) {
  Handle(TDataStd_Name) name;
  if (!label.FindAttribute(TDataStd_Name::GetID(), name)) return {};
  // Converting an extended (UTF-16) string without a replacement character yields UTF-8.
  return TCollection_AsciiString(name->Get()).ToCString();
}

Eigen::Vector3f ToVector(const Quantity_Color& c) {
  double r, g, b;
  c.Values(r, g, b, Quantity_TOC_sRGB);
  return Eigen::Vector3f(float(r), float(g), float(b));
}

std::optional<Eigen::Vector3f> LabelColor(const Handle(XCAFDoc_ColorTool) & colors,
                                          const TDF_Label& label) {
  Quantity_Color c;
  if (colors->GetColor(label, XCAFDoc_ColorSurf, c) ||
      colors->GetColor(label, XCAFDoc_ColorGen, c)) {
    return ToVector(c);
  }
  return std::nullopt;
}

std::optional<Eigen::Vector3f> ShapeColor(const Handle(XCAFDoc_ColorTool) & colors,
                                          const TopoDS_Shape& shape) {
  Quantity_Color c;
  if (colors->GetColor(shape, XCAFDoc_ColorSurf, c) ||
      colors->GetColor(shape, XCAFDoc_ColorGen, c)) {
    return ToVector(c);
  }
  return std::nullopt;
}

// A part's colour: its label's, else its first coloured solid's, else the colour covering the
// largest area of its faces (files that colour faces only).
std::optional<Eigen::Vector3f> PartColor(const Handle(XCAFDoc_ColorTool) & colors,
                                         const TDF_Label& label, const TopoDS_Shape& shape) {
  if (auto c = LabelColor(colors, label)) return c;
  for (TopExp_Explorer it(shape, TopAbs_SOLID); it.More(); it.Next()) {
    if (auto c = ShapeColor(colors, it.Current())) return c;
  }
  std::map<std::array<float, 3>, double> area;
  for (TopExp_Explorer it(shape, TopAbs_FACE); it.More(); it.Next()) {
    if (auto c = ShapeColor(colors, it.Current())) {
      GProp_GProps props;
      BRepGProp::SurfaceProperties(it.Current(), props);
      area[{c->x(), c->y(), c->z()}] += props.Mass();
    }
  }
  if (area.empty()) return std::nullopt;
  const auto best = std::max_element(
      area.begin(), area.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
  return Eigen::Vector3f(best->first[0], best->first[1], best->first[2]);
}

Eigen::Isometry3d ToIsometry(const gp_Trsf& trsf, const std::string& where) {
  gp_Trsf t = trsf;
  if (std::abs(t.ScaleFactor() - 1.0) > 1e-9) {
    Warn(where + ": placement has scale factor " + std::to_string(t.ScaleFactor()) +
         "; the scale is ignored");
    t.SetScaleFactor(1.0);
  }
  Eigen::Isometry3d result = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) result.linear()(r, c) = t.Value(r + 1, c + 1);
    result.translation()(r) = t.Value(r + 1, 4);
  }
  return result;
}

struct Walker {
  const std::string& file;
  Handle(XCAFDoc_ColorTool) colors;
  CadContents* out;
  std::map<std::string, int> part_by_entry;

  void Visit(const TDF_Label& label, const TopLoc_Location& location, const std::string& name,
             const std::string& path, std::optional<Eigen::Vector3f> color) {
    if (XCAFDoc_ShapeTool::IsAssembly(label)) {
      if (!color) color = LabelColor(colors, label);
      TDF_LabelSequence components;
      XCAFDoc_ShapeTool::GetComponents(label, components, /*getsubchilds=*/false);
      for (TDF_LabelSequence::Iterator it(components); it.More(); it.Next()) {
        TDF_Label referred;
        if (!XCAFDoc_ShapeTool::GetReferredShape(it.Value(), referred)) continue;
        std::optional<Eigen::Vector3f> own = LabelColor(colors, it.Value());
        const std::string child = LabelName(it.Value());
        Visit(referred, location * XCAFDoc_ShapeTool::GetLocation(it.Value()), child,
              path + "/" + (child.empty() ? LabelName(referred) : child), own ? own : color);
      }
      return;
    }
    TCollection_AsciiString entry;
    TDF_Tool::Entry(label, entry);
    auto [slot, inserted] =
        part_by_entry.emplace(entry.ToCString(), static_cast<int>(out->part_names.size()));
    if (inserted) {
      std::string part_name = LabelName(label);
      if (part_name.empty()) part_name = "part_" + std::to_string(out->part_names.size());
      out->part_names.push_back(part_name);
      const TopoDS_Shape shape = XCAFDoc_ShapeTool::GetShape(label);
      out->part_shapes.push_back(WrapShape(shape));
      out->part_colors.push_back(PartColor(colors, label, shape));
    }
    Instance instance;
    instance.part = slot->second;
    instance.name = name.empty() ? out->part_names[slot->second] : name;
    instance.path = path;
    instance.world_from_model =
        ToIsometry(location.Transformation(), file + ": instance '" + instance.name + "'");
    instance.color = color;
    out->instances.push_back(std::move(instance));
  }
};

}  // namespace

void InitOcct() {
  static std::once_flag once;
  std::call_once(once, [] {
    const Handle(Message_Messenger)& messenger = Message::DefaultMessenger();
    for (Message_SequenceOfPrinters::Iterator it(messenger->Printers()); it.More(); it.Next()) {
      it.Value()->SetTraceLevel(Message_Fail);
    }
    Interface_Static::SetCVal("xstep.cascade.unit", "MM");
    Interface_Static::SetCVal("write.step.unit", "MM");
  });
}

DocumentGuard::DocumentGuard() {
  XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", doc);
}
DocumentGuard::~DocumentGuard() { XCAFApp_Application::GetApplication()->Close(doc); }

std::mutex& XdeMutex() {
  static std::mutex mutex;
  return mutex;
}

void RequireReadableFile(const std::string& file) {
  std::error_code ec;
  const std::filesystem::path path(file);
  if (!std::filesystem::exists(path, ec)) throw Error(file + ": no such file");
  if (std::filesystem::is_directory(path, ec)) throw Error(file + ": is a folder, not a file");
  if (!std::filesystem::is_regular_file(path, ec)) throw Error(file + ": not a regular file");
  if (std::filesystem::file_size(path, ec) == 0) throw Error(file + ": file is empty");
}

CadContents CollectDocument(const Handle(TDocStd_Document) & doc, const std::string& file) {
  CadContents contents;
  const Handle(XCAFDoc_ShapeTool) shapes = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
  Walker walker{file, XCAFDoc_DocumentTool::ColorTool(doc->Main()), &contents, {}};
  TDF_LabelSequence roots;
  shapes->GetFreeShapes(roots);
  for (TDF_LabelSequence::Iterator it(roots); it.More(); it.Next()) {
    if (contents.name.empty()) contents.name = LabelName(it.Value());
    const std::string root = LabelName(it.Value());
    walker.Visit(it.Value(), TopLoc_Location(), root, root.empty() ? "root" : root, std::nullopt);
  }
  return contents;
}

Assembly BuildAssembly(const std::string& file, CadContents contents,
                       const TessellationOptions& options) {
  const size_t n = contents.part_shapes.size();
  std::vector<Part> parts(n);
  std::vector<std::string> errors(n);
  std::vector<std::vector<std::string>> warnings(n);  // reported in part order, not thread order
  tbb::parallel_for(size_t{0}, n, [&](size_t i) {
    WarningCapture capture;
    try {
      bool healed = false;
      const Shape shape = Heal(contents.part_shapes[i], &healed);
      if (healed)
        Warn(file + ": part '" + contents.part_names[i] +
             "' had invalid geometry; repaired by shape healing");
      parts[i] = MakePart(contents.part_names[i], shape, options);
      parts[i].color = contents.part_colors[i];
    } catch (const Error& e) {
      errors[i] = e.what();
    } catch (const Standard_Failure& failure) {
      errors[i] = std::string("OpenCASCADE failed: ") + failure.GetMessageString();
    }
    warnings[i] = capture.Take();
  });
  for (const auto& part_warnings : warnings) {
    for (const std::string& warning : part_warnings) Warn(warning);
  }
  Assembly assembly;
  assembly.name =
      contents.name.empty() ? std::filesystem::path(file).stem().string() : contents.name;
  std::vector<int> new_index(n, -1);
  for (size_t i = 0; i < n; ++i) {
    if (!errors[i].empty()) {
      Warn(file + ": part '" + contents.part_names[i] + "' skipped: " + errors[i]);
      continue;
    }
    if (!parts[i].watertight) {
      Warn(file + ": part '" + parts[i].name + "' is not closed (its tessellation has holes)");
    }
    new_index[i] = static_cast<int>(assembly.parts.size());
    assembly.parts.push_back(std::move(parts[i]));
  }
  if (assembly.parts.empty()) throw Error(file + ": no geometry to tessellate in this file");
  for (Instance& instance : contents.instances) {
    const int part = new_index[instance.part];
    if (part < 0) continue;
    instance.part = part;
    instance.world_from_model = instance.world_from_model * assembly.parts[part].cad_from_model;
    assembly.instances.push_back(std::move(instance));
  }
  return assembly;
}

std::string PlainFailure(const Standard_Failure& failure) {
  const std::string kind = failure.DynamicType()->Name();
  std::string message = failure.GetMessageString() ? failure.GetMessageString() : "";
  // A class or function name (NCollection_Sequence::Value, BRep_Tool::Curve) is no explanation.
  const bool sentence =
      message.find(' ') != std::string::npos && message.find("::") == std::string::npos;
  if (sentence) return message.size() > 200 ? message.substr(0, 200) + "..." : message;
  static const std::pair<const char*, const char*> kMeanings[] = {
      {"Standard_OutOfRange", "a value out of range (a damaged index or count?)"},
      {"Standard_RangeError", "a value out of range (a damaged index or count?)"},
      {"Standard_NoSuchObject", "a reference to something the file does not hold"},
      {"Standard_NullObject", "a reference to something the file does not hold"},
      {"Standard_ConstructionError", "a curve or surface that cannot be built from its numbers"},
      {"Standard_DomainError", "a curve or surface that cannot be built from its numbers"},
      {"Standard_DivideByZero", "a division by zero on the file's numbers"},
      {"Standard_NumericError", "a numeric error on the file's numbers"},
      {"Standard_Overflow", "a numeric overflow on the file's numbers"},
      {"Standard_OutOfMemory", "not enough memory"},
      {"Storage_StreamFormatError", "data that do not follow the format (a cut or damaged file?)"},
      {"Storage_StreamReadError", "data that do not follow the format (a cut or damaged file?)"},
  };
  for (const auto& [name, meaning] : kMeanings) {
    if (kind == name) return meaning;
  }
  return "an internal failure of its reader (" + kind + ")";
}

}  // namespace cadsynth::internal
