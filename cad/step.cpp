#include "cad/step.h"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <vector>

#include <IFSelect_ReturnStatus.hxx>
#include <Interface_Check.hxx>
#include <Interface_CheckIterator.hxx>
#include <Interface_Static.hxx>
#include <Quantity_Color.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <STEPCAFControl_Writer.hxx>
#include <STEPControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_SequenceOfAsciiString.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopLoc_Location.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <XSControl_WorkSession.hxx>

#include "cad/core/error.h"
#include "cad/core/units.h"
#include "cad/occt_shape.h"
#include "cad/step_tessellated.h"
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

bool IsValidUtf8(const std::string& bytes) {
  size_t i = 0;
  while (i < bytes.size()) {
    const auto c = static_cast<unsigned char>(bytes[i]);
    const int extra = c < 0x80           ? 0
                      : (c >> 5) == 0x6  ? 1
                      : (c >> 4) == 0xE  ? 2
                      : (c >> 3) == 0x1E ? 3
                                         : -1;
    if (extra < 0 || i + extra >= bytes.size() + (extra == 0 ? 1 : 0)) return false;
    for (int k = 1; k <= extra; ++k) {
      if ((static_cast<unsigned char>(bytes[i + k]) >> 6) != 0x2) return false;
    }
    i += extra + 1;
  }
  return true;
}

// STEP strings are ASCII with escapes; some writers put raw bytes of their code page instead.
// Warn when those bytes are not UTF-8, so the user can state the code page.
void WarnOnRawNonUtf8(const std::filesystem::path& path, const std::string& file) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  while (std::getline(in, line)) {
    const bool raw = std::any_of(line.begin(), line.end(),
                                 [](char c) { return static_cast<unsigned char>(c) >= 0x80; });
    if (raw && !IsValidUtf8(line)) {
      Warn(file +
           ": names hold bytes that are not UTF-8 (a local code page); state it, e.g. "
           "`encoding: cp1251` for Cyrillic, `cp1252` for Western European, `sjis` for Japanese");
      return;
    }
  }
}

// OpenCASCADE's STEP parser recurses once per nested parenthesis: a file nested 200,000 deep
// exhausts the stack (SIGSEGV). Real files nest a few levels; refuse absurd ones before parsing.
// Parentheses inside strings ('...', with '' for a quote) and comments (/* */) do not count.
void RejectDeepNesting(const std::filesystem::path& path, const std::string& file) {
  constexpr int kMaxDepth = 1000;
  std::ifstream in(path, std::ios::binary);
  std::vector<char> buffer(1 << 16);
  int depth = 0;
  size_t line = 1;
  bool in_string = false, in_comment = false;
  char previous = 0;
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    const std::streamsize n = in.gcount();
    for (std::streamsize i = 0; i < n; ++i) {
      const char c = buffer[static_cast<size_t>(i)];
      if (c == '\n') ++line;
      if (in_comment) {
        if (previous == '*' && c == '/')
          in_comment = false, previous = 0;
        else
          previous = c;
        continue;
      }
      if (in_string) {
        if (c == '\'') in_string = false;  // '' is a closing and an opening quote
      } else if (c == '\'') {
        in_string = true;
      } else if (c == '*' && previous == '/') {
        in_comment = true;
      } else if (c == '(') {
        if (++depth > kMaxDepth) {
          throw Error(file + ":" + std::to_string(line) + ": parentheses nested more than " +
                      std::to_string(kMaxDepth) + " deep: not a STEP file cadsynth can read");
        }
      } else if (c == ')') {
        depth = std::max(0, depth - 1);
      }
      previous = c;
    }
  }
}

}  // namespace

std::string StepCodePage(const std::string& encoding) {
  static const char* const kNames[] = {
      "UTF8",      "SJIS",      "EUC",       "GB",        "CP850",     "CP1250",
      "CP1251",    "CP1252",    "CP1253",    "CP1254",    "CP1255",    "CP1256",
      "CP1257",    "CP1258",    "iso8859-1", "iso8859-2", "iso8859-3", "iso8859-4",
      "iso8859-5", "iso8859-6", "iso8859-7", "iso8859-8", "iso8859-9"};
  static const std::pair<const char*, const char*> kAliases[] = {
      {"utf-8", "UTF8"}, {"shift_jis", "SJIS"},   {"shift-jis", "SJIS"},   {"gb2312", "GB"},
      {"gbk", "GB"},     {"latin1", "iso8859-1"}, {"latin-1", "iso8859-1"}};
  const auto lower = [](std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
  };
  const std::string key = lower(encoding);
  for (const auto& [alias, name] : kAliases) {
    if (key == alias) return name;
  }
  for (const char* name : kNames) {
    if (key == lower(name)) return name;
  }
  return {};
}

Assembly ReadStep(const std::filesystem::path& path, const TessellationOptions& options,
                  const std::string& encoding) {
  const std::string file = path.string();
  internal::RequireReadableFile(file);
  std::string why;
  if (!options.Check(&why)) throw Error(file + ": tessellation: " + why);
  const std::string code_page = encoding.empty() ? "UTF8" : StepCodePage(encoding);
  if (code_page.empty()) throw Error(file + ": unknown encoding '" + encoding + "'");
  RejectDeepNesting(path, file);
  if (encoding.empty()) WarnOnRawNonUtf8(path, file);
  internal::InitOcct();

  internal::CadContents contents;
  std::string length_unit;
  {
    std::lock_guard<std::mutex> lock(internal::XdeMutex());
    try {
      internal::DocumentGuard document;
      Interface_Static::SetCVal("read.step.codepage", code_page.c_str());  // under XdeMutex
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
      throw Error(file + ": cannot read: " + internal::PlainFailure(failure));
    }
  }
  // Files that carry only triangles (AP242 tessellated geometry) have no B-rep faces for
  // OpenCASCADE 7.6: pass their triangles through.
  const bool has_faces = std::any_of(contents.part_shapes.begin(), contents.part_shapes.end(),
                                     [](const Shape& s) { return s.HasFaces(); });
  if (!has_faces) {
    const std::optional<double> unit_mm = LengthUnitMm(length_unit);
    Assembly tessellated = internal::ReadStepTessellated(path, unit_mm.value_or(1.0));
    if (!tessellated.parts.empty()) {
      tessellated.name = contents.name.empty() ? path.stem().string() : contents.name;
      tessellated.format = "STEP (tessellated)";
      tessellated.length_unit = length_unit;
      return tessellated;
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
    internal::DocumentGuard document;
    const Handle(XCAFDoc_ShapeTool) tool = XCAFDoc_DocumentTool::ShapeTool(document.doc->Main());
    const TDF_Label root = tool->NewShape();
    TDataStd_Name::Set(root, TCollection_ExtendedString(assembly_name.c_str(), true));
    for (const StepComponent& component : components) {
      if (component.shape.IsNull()) fail("component '" + component.name + "' is empty");
      const TDF_Label part = tool->AddShape(OcctShape(component.shape), /*makeAssembly=*/false);
      TDataStd_Name::Set(part, TCollection_ExtendedString(component.name.c_str(), true));
      if (component.color) {
        const Eigen::Vector3f& c = *component.color;
        XCAFDoc_DocumentTool::ColorTool(document.doc->Main())
            ->SetColor(part, Quantity_Color(c.x(), c.y(), c.z(), Quantity_TOC_sRGB),
                       XCAFDoc_ColorSurf);
      }
      for (size_t k = 0; k < component.placements.size(); ++k) {
        const TDF_Label placed =
            tool->AddComponent(root, part, TopLoc_Location(ToTrsf(component.placements[k])));
        const std::string name = component.name + "_" + std::to_string(k + 1);
        TDataStd_Name::Set(placed, TCollection_ExtendedString(name.c_str(), true));
      }
    }
    tool->UpdateAssemblies();
    STEPCAFControl_Writer writer;
    writer.SetNameMode(true);
    writer.SetColorMode(true);
    if (!writer.Transfer(document.doc, STEPControl_AsIs)) {
      fail("OpenCASCADE could not translate the shapes to STEP");
    }
    if (writer.Write(temporary.string().c_str()) != IFSelect_RetDone)
      fail("could not write the STEP file");
  } catch (const Standard_Failure& failure) {
    fail(std::string("OpenCASCADE failed while writing: ") + internal::PlainFailure(failure));
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) fail("could not move the written file into place: " + ec.message());
}

}  // namespace cadsynth
