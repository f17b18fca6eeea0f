#include "cad/step.h"

#include <IFSelect_ReturnStatus.hxx>
#include <Interface_Check.hxx>
#include <Interface_CheckIterator.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <STEPCAFControl_Writer.hxx>
#include <STEPControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_SequenceOfAsciiString.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopLoc_Location.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <XSControl_WorkSession.hxx>

#include "cad/error.h"
#include "cad/occt_shape.h"
#include "cad/xde.h"

namespace cadsynth {
namespace {

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

// Closes an XDE document when it goes out of scope.
struct DocumentGuard {
  Handle(TDocStd_Document) doc;
  DocumentGuard() { XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", doc); }
  ~DocumentGuard() { XCAFApp_Application::GetApplication()->Close(doc); }
};

}  // namespace

Assembly ReadStep(const std::filesystem::path& path, const TessellationOptions& options) {
  const std::string file = path.string();
  internal::RequireReadableFile(file);
  std::string why;
  if (!options.Check(&why)) throw Error(file + ": tessellation: " + why);
  internal::InitOcct();

  internal::CadContents contents;
  std::string length_unit;
  {
    std::lock_guard<std::mutex> lock(internal::XdeMutex());
    try {
      DocumentGuard document;
      STEPCAFControl_Reader reader;
      reader.SetNameMode(true);
      reader.SetColorMode(true);
      reader.SetLayerMode(false);
      reader.SetPropsMode(false);
      // OpenCASCADE resolves external references (DOCUMENT_FILE) against the path as given:
      // make it absolute, or assemblies split over files lose their parts unless read from
      // their own folder.
      const std::string absolute = std::filesystem::absolute(path).lexically_normal().string();
      if (reader.ReadFile(absolute.c_str()) != IFSelect_RetDone) {
        throw Error(file + ": not a readable STEP file (OpenCASCADE could not parse it)");
      }
      ThrowOnSyntaxErrors(reader.ChangeReader(), file);
      TColStd_SequenceOfAsciiString lengths, angles, solid_angles;
      reader.ChangeReader().FileUnits(lengths, angles, solid_angles);
      if (!lengths.IsEmpty()) length_unit = lengths.First().ToCString();
      if (!reader.Transfer(document.doc)) {
        throw Error(file + ": OpenCASCADE could not translate the STEP entities into shapes");
      }
      contents = internal::CollectDocument(document.doc, file);
    } catch (const Standard_Failure& failure) {
      throw Error(file + ": OpenCASCADE failed while reading: " + failure.GetMessageString());
    }
  }
  Assembly assembly = internal::BuildAssembly(file, std::move(contents), options);
  assembly.format = "STEP";
  assembly.length_unit = length_unit;
  return assembly;
}

void WriteStep(const std::filesystem::path& path, const std::string& assembly_name,
               const std::vector<StepComponent>& components) {
  internal::InitOcct();
  const std::string file = path.string();
  const std::filesystem::path temporary = path.string() + ".partial";
  const auto fail = [&](const std::string& why) {
    std::error_code ec;
    std::filesystem::remove(temporary, ec);
    throw Error(file + ": " + why);
  };
  std::lock_guard<std::mutex> lock(internal::XdeMutex());
  try {
    DocumentGuard document;
    const Handle(XCAFDoc_ShapeTool) tool = XCAFDoc_DocumentTool::ShapeTool(document.doc->Main());
    const TDF_Label root = tool->NewShape();
    TDataStd_Name::Set(root, TCollection_ExtendedString(assembly_name.c_str(), true));
    for (const StepComponent& component : components) {
      if (component.shape.IsNull()) fail("component '" + component.name + "' is empty");
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
    if (!writer.Transfer(document.doc, STEPControl_AsIs)) {
      fail("OpenCASCADE could not translate the shapes to STEP");
    }
    if (writer.Write(temporary.string().c_str()) != IFSelect_RetDone) fail("could not write the STEP file");
  } catch (const Standard_Failure& failure) {
    fail(std::string("OpenCASCADE failed while writing: ") + failure.GetMessageString());
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) fail("could not move the written file into place: " + ec.message());
}

}  // namespace cadsynth
