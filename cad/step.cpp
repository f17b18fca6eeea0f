#include "cad/step.h"

#include <cmath>
#include <map>
#include <mutex>
#include <system_error>

#include <IFSelect_ReturnStatus.hxx>
#include <Interface_Check.hxx>
#include <Interface_CheckIterator.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_Printer.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <STEPCAFControl_Writer.hxx>
#include <STEPControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <TCollection_AsciiString.hxx>
#include <TColStd_SequenceOfAsciiString.hxx>
#include <TDF_Label.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDF_Tool.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopLoc_Location.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <XSControl_WorkSession.hxx>
#include <gp_Trsf.hxx>
#include <tbb/parallel_for.h>

#include "cad/error.h"
#include "cad/occt_shape.h"

namespace cadsynth {
namespace {

// OpenCASCADE prints translation chatter to stdout; keep only failures (we report those).
void QuietOcctOnce() {
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

// XDE documents are created through a process-wide application object; keep access serial.
std::mutex& XdeMutex() {
  static std::mutex mutex;
  return mutex;
}

std::string LabelName(const TDF_Label& label) {
  Handle(TDataStd_Name) name;
  if (!label.FindAttribute(TDataStd_Name::GetID(), name)) return {};
  // Converting an extended (UTF-16) string without a replacement character yields UTF-8.
  return TCollection_AsciiString(name->Get()).ToCString();
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

// OpenCASCADE reads past syntax errors and quietly drops the entities it could not parse, which
// turns a corrupted file into plausible but wrong geometry. Syntax failures sit in the model's
// global check (entity number 0); per-entity semantic failures (unusual PMI or font entities in
// real files) do not make a file unusable and are tolerated.
void ThrowOnSyntaxErrors(STEPControl_Reader& reader, const std::string& file) {
  const Interface_CheckIterator checks = reader.WS()->ModelCheckList();
  for (checks.Start(); checks.More(); checks.Next()) {
    const Handle(Interface_Check)& check = checks.Value();
    if (checks.Number() != 0 || check->NbFails() == 0) continue;
    std::string first = check->CFail(1);
    const std::string prefix = "Undefined Parsing: ";
    if (first.rfind(prefix, 0) == 0) first = first.substr(prefix.size());
    throw Error(file + ": corrupted STEP file: " + first + " (" + std::to_string(check->NbFails()) +
                " syntax error" + (check->NbFails() > 1 ? "s" : "") + ")");
  }
}

struct PendingInstance {
  TDF_Label prototype;
  std::string name;
  TopLoc_Location location;
};

void Collect(const TDF_Label& label, const TopLoc_Location& location, const std::string& name,
             std::vector<PendingInstance>* out) {
  if (XCAFDoc_ShapeTool::IsAssembly(label)) {
    TDF_LabelSequence components;
    XCAFDoc_ShapeTool::GetComponents(label, components, /*getsubchilds=*/false);
    for (TDF_LabelSequence::Iterator it(components); it.More(); it.Next()) {
      TDF_Label referred;
      if (!XCAFDoc_ShapeTool::GetReferredShape(it.Value(), referred)) continue;
      Collect(referred, location * XCAFDoc_ShapeTool::GetLocation(it.Value()),
              LabelName(it.Value()), out);
    }
    return;
  }
  out->push_back({label, name, location});
}

}  // namespace

Assembly ReadStep(const std::filesystem::path& path, const TessellationOptions& options) {
  const std::string file = path.string();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw Error(file + ": no such file");
  if (std::filesystem::is_directory(path, ec)) throw Error(file + ": is a folder, not a file");
  if (std::filesystem::file_size(path, ec) == 0) throw Error(file + ": file is empty");
  std::string why;
  if (!options.Check(&why)) throw Error(file + ": tessellation: " + why);
  QuietOcctOnce();

  Assembly assembly;
  std::vector<PendingInstance> pending;
  std::map<int, int> part_of_prototype;  // pending index of first use -> part index
  std::vector<Shape> shapes;
  {
    std::lock_guard<std::mutex> lock(XdeMutex());
    try {
      Handle(TDocStd_Document) doc;
      XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", doc);
      STEPCAFControl_Reader reader;
      reader.SetNameMode(true);
      reader.SetColorMode(true);
      reader.SetLayerMode(false);
      reader.SetPropsMode(false);
      if (reader.ReadFile(file.c_str()) != IFSelect_RetDone) {
        XCAFApp_Application::GetApplication()->Close(doc);
        throw Error(file + ": not a readable STEP file (OpenCASCADE could not parse it)");
      }
      ThrowOnSyntaxErrors(reader.ChangeReader(), file);
      {
        TColStd_SequenceOfAsciiString lengths, angles, solid_angles;
        reader.ChangeReader().FileUnits(lengths, angles, solid_angles);
        if (!lengths.IsEmpty()) assembly.length_unit = lengths.First().ToCString();
      }
      if (!reader.Transfer(doc)) {
        XCAFApp_Application::GetApplication()->Close(doc);
        throw Error(file + ": OpenCASCADE could not translate the STEP entities into shapes");
      }
      const Handle(XCAFDoc_ShapeTool) tool = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
      TDF_LabelSequence roots;
      tool->GetFreeShapes(roots);
      for (TDF_LabelSequence::Iterator it(roots); it.More(); it.Next()) {
        if (assembly.name.empty()) assembly.name = LabelName(it.Value());
        Collect(it.Value(), TopLoc_Location(), LabelName(it.Value()), &pending);
      }
      // One part per distinct prototype label.
      std::map<std::string, int> part_by_entry;
      for (size_t i = 0; i < pending.size(); ++i) {
        TCollection_AsciiString entry;
        TDF_Tool::Entry(pending[i].prototype, entry);
        auto [slot, inserted] =
            part_by_entry.emplace(entry.ToCString(), static_cast<int>(assembly.parts.size()));
        if (inserted) {
          Part part;
          part.name = LabelName(pending[i].prototype);
          if (part.name.empty()) part.name = "part_" + std::to_string(assembly.parts.size());
          assembly.parts.push_back(std::move(part));
          shapes.push_back(WrapShape(XCAFDoc_ShapeTool::GetShape(pending[i].prototype)));
        }
        part_of_prototype[static_cast<int>(i)] = slot->second;
      }
      XCAFApp_Application::GetApplication()->Close(doc);
    } catch (const Standard_Failure& failure) {
      throw Error(file + ": OpenCASCADE failed while reading: " + failure.GetMessageString());
    }
  }

  // Tessellate distinct parts in parallel; parts without faces are dropped with a warning.
  std::vector<std::string> errors(shapes.size());
  tbb::parallel_for(size_t{0}, shapes.size(), [&](size_t i) {
    try {
      assembly.parts[i] = MakePart(assembly.parts[i].name, shapes[i], options);
    } catch (const Error& e) {
      errors[i] = e.what();
    } catch (const Standard_Failure& failure) {
      errors[i] = std::string("OpenCASCADE failed: ") + failure.GetMessageString();
    }
  });
  std::vector<int> new_index(shapes.size(), -1);
  std::vector<Part> kept;
  for (size_t i = 0; i < shapes.size(); ++i) {
    if (!errors[i].empty()) {
      Warn(file + ": part '" + assembly.parts[i].name + "' skipped: " + errors[i]);
      continue;
    }
    new_index[i] = static_cast<int>(kept.size());
    kept.push_back(std::move(assembly.parts[i]));
  }
  assembly.parts = std::move(kept);
  if (assembly.parts.empty()) throw Error(file + ": no geometry to tessellate in this file");

  for (size_t i = 0; i < pending.size(); ++i) {
    const int part = new_index[part_of_prototype[static_cast<int>(i)]];
    if (part < 0) continue;
    Instance instance;
    instance.part = part;
    instance.name = pending[i].name.empty() ? assembly.parts[part].name : pending[i].name;
    instance.world_from_model =
        ToIsometry(pending[i].location.Transformation(), file + ": instance '" + instance.name + "'") *
        assembly.parts[part].cad_from_model;
    assembly.instances.push_back(std::move(instance));
  }
  if (assembly.name.empty()) assembly.name = path.stem().string();
  return assembly;
}

void WriteStep(const std::filesystem::path& path, const std::string& assembly_name,
               const std::vector<StepComponent>& components) {
  QuietOcctOnce();
  const std::string file = path.string();
  const std::filesystem::path temporary = path.string() + ".partial";
  std::lock_guard<std::mutex> lock(XdeMutex());
  try {
    Handle(TDocStd_Document) doc;
    XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", doc);
    const Handle(XCAFDoc_ShapeTool) tool = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
    const TDF_Label root = tool->NewShape();
    TDataStd_Name::Set(root, TCollection_ExtendedString(assembly_name.c_str(), true));
    for (const StepComponent& component : components) {
      if (component.shape.IsNull()) throw Error(file + ": component '" + component.name + "' is empty");
      const TDF_Label part = tool->AddShape(OcctShape(component.shape), /*makeAssembly=*/false);
      TDataStd_Name::Set(part, TCollection_ExtendedString(component.name.c_str(), true));
      for (const Eigen::Isometry3d& placement : component.placements) {
        tool->AddComponent(root, part, TopLoc_Location(ToTrsf(placement)));
      }
    }
    tool->UpdateAssemblies();
    STEPCAFControl_Writer writer;
    writer.SetNameMode(true);
    writer.SetColorMode(true);
    if (!writer.Transfer(doc, STEPControl_AsIs)) {
      XCAFApp_Application::GetApplication()->Close(doc);
      throw Error(file + ": OpenCASCADE could not translate the shapes to STEP");
    }
    const IFSelect_ReturnStatus status = writer.Write(temporary.string().c_str());
    XCAFApp_Application::GetApplication()->Close(doc);
    if (status != IFSelect_RetDone) {
      std::error_code ec;
      std::filesystem::remove(temporary, ec);
      throw Error(file + ": could not write the STEP file");
    }
  } catch (const Standard_Failure& failure) {
    std::error_code ec;
    std::filesystem::remove(temporary, ec);
    throw Error(file + ": OpenCASCADE failed while writing: " + failure.GetMessageString());
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) throw Error(file + ": could not move the written file into place: " + ec.message());
}

}  // namespace cadsynth
