// The importer against real third-party files (skipped without ../shared/data) and bad input.
#include "cad/import.h"

#include <cctype>
#include <fstream>
#include <map>

#include <gtest/gtest.h>

#include <BRepTools.hxx>
#include <IGESControl_Writer.hxx>
#include <Standard_DomainError.hxx>
#include <Standard_OutOfRange.hxx>

#include "cad/core/error.h"
#include "cad/occt_shape.h"
#include "cad/step.h"
#include "cad/step_tessellated.h"
#include "cad/xde.h"
#include "tests/test_support.h"

namespace cadsynth {
namespace {

using testing::ScratchDir;

ImportOptions Coarse(const std::string& unit = "") {
  ImportOptions o;
  o.tessellation.linear_deflection_mm = 0.5;
  o.unit = unit;
  return o;
}

std::string ErrorOf(const std::filesystem::path& path, const ImportOptions& o = Coarse()) {
  try {
    ImportCad(path, o);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

// Silences warnings for the duration of a test and counts them.
class QuietWarnings {
 public:
  QuietWarnings() : previous_(SetWarningSink([](const std::string&) { ++count_; })) { count_ = 0; }
  ~QuietWarnings() { SetWarningSink(previous_); }
  static int count() { return count_; }

 private:
  static inline int count_ = 0;
  WarningSink previous_;
};

TEST(ImportSharedData, EveryFileImportsOrFailsWithAMessageNamingIt) {
  const std::filesystem::path root = testing::DataDir();
  if (!std::filesystem::exists(root / "step"))
    GTEST_SKIP() << "shared test data not found: " << root;
  QuietWarnings quiet;
  int imported = 0;
  std::vector<std::string> failed;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
    if (!entry.is_regular_file()) continue;
    const std::string ext = entry.path().extension().string();
    if (ext == ".md" || entry.path().filename() == "SHA256SUMS") continue;
    try {
      const Assembly a = ImportCad(entry.path(), Coarse());
      ASSERT_FALSE(a.parts.empty()) << entry.path();
      ASSERT_FALSE(a.instances.empty()) << entry.path();
      for (const Part& p : a.parts) {
        ASSERT_FALSE(p.mesh.empty()) << entry.path();
        ASSERT_TRUE(p.mesh.Bounds().sizes().allFinite()) << entry.path();
      }
      ++imported;
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind(entry.path().string() + ": ", 0), 0u) << e.what();
      failed.push_back(entry.path().filename().string());
    }
  }
  // The deliberately corrupted file is the only one that does not import.
  EXPECT_EQ(failed, std::vector<std::string>{"bug32314_corrupted.stp"});
  EXPECT_GE(imported, 60);
}

// Instance boxes in the assembly frame, all instances together.
Eigen::AlignedBox3d AssemblyBounds(const Assembly& a) {
  Eigen::AlignedBox3d box;
  for (const Instance& i : a.instances) box.extend(a.parts[i.part].mesh.Bounds(i.world_from_model));
  return box;
}

std::string Canonical(std::string name) {
  std::string out;
  for (char c : name) {
    if (std::isalnum(static_cast<unsigned char>(c))) out += static_cast<char>(std::tolower(c));
  }
  return out;
}

TEST(ImportSharedData, As1FromTwoWritersGivesTheSameParts) {
  CADSYNTH_REQUIRE_DATA(oc, "step/assemblies/as1-oc-214.stp");
  CADSYNTH_REQUIRE_DATA(md, "step/assemblies/as1-md-214.stp");
  const Assembly a = ImportCad(oc, Coarse()), b = ImportCad(md, Coarse());
  std::map<std::string, const Part*> pa, pb;
  std::map<std::string, int> ca, cb;
  for (const Part& p : a.parts) pa[Canonical(p.name)] = &p;
  for (const Part& p : b.parts) pb[Canonical(p.name)] = &p;
  for (const Instance& i : a.instances) ++ca[Canonical(a.parts[i.part].name)];
  for (const Instance& i : b.instances) ++cb[Canonical(b.parts[i.part].name)];
  ASSERT_EQ(pa.size(), 5u);
  ASSERT_EQ(pb.size(), 5u);
  EXPECT_EQ(ca, cb);  // plate 1, l-bracket 2, rod 1, bolt 6, nut 8
  for (const auto& [name, part] : pa) {
    ASSERT_TRUE(pb.count(name)) << name;
    if (name == "bolt") continue;  // the MicroStation file's bolt is 40 mm long, OCCT's 37 mm
    EXPECT_NEAR(part->mass.volume_mm3, pb[name]->mass.volume_mm3, 1e-3 * part->mass.volume_mm3)
        << name;
    std::vector<double> sa(3), sb(3);
    for (int k = 0; k < 3; ++k) {
      sa[k] = std::round(part->mesh.Bounds().sizes()[k] * 10) / 10;
      sb[k] = std::round(pb[name]->mesh.Bounds().sizes()[k] * 10) / 10;
    }
    std::sort(sa.begin(), sa.end());  // the writers orient some part frames differently
    std::sort(sb.begin(), sb.end());
    EXPECT_EQ(sa, sb) << name;
  }
  EXPECT_NEAR(pa["bolt"]->mesh.Bounds().sizes().maxCoeff(), 37.0, 0.01);
  EXPECT_NEAR(pb["bolt"]->mesh.Bounds().sizes().maxCoeff(), 40.0, 0.01);
  // Same footprint; the longer bolts reach 3 mm further below the plate.
  const Eigen::Vector3d size_a = AssemblyBounds(a).sizes(), size_b = AssemblyBounds(b).sizes();
  EXPECT_NEAR(size_a.x(), 200.0, 0.01);
  EXPECT_NEAR(size_b.x(), 200.0, 0.01);
  EXPECT_NEAR(size_a.y(), 150.0, 0.01);
  EXPECT_NEAR(size_b.y(), 150.0, 0.01);
  EXPECT_NEAR(size_b.z() - size_a.z(), 3.0, 0.01);
}

TEST(ImportSharedData, InchFileComesOutInMillimetres) {
  CADSYNTH_REQUIRE_DATA(file, "step/assemblies/dm1-id-214.stp");
  const Assembly inch = ImportCad(file, Coarse());
  const Assembly raw = ImportCad(file, Coarse("mm"));  // the file's numbers taken as mm
  EXPECT_EQ(inch.length_unit, "INCH");
  ASSERT_EQ(inch.parts.size(), raw.parts.size());
  for (size_t i = 0; i < inch.parts.size(); ++i) {
    const Eigen::Vector3d a = inch.parts[i].mesh.Bounds().sizes(),
                          b = raw.parts[i].mesh.Bounds().sizes();
    EXPECT_TRUE(a.isApprox(25.4 * b, 1e-4))
        << inch.parts[i].name << ": " << a.transpose() << " vs " << b.transpose();
  }
}

TEST(ImportSharedData, UnitOverrideRepairsTheFileThatDeclaresInchButHoldsMillimetres) {
  CADSYNTH_REQUIRE_DATA(pe, "step/assemblies/as1_pe_203.stp");
  CADSYNTH_REQUIRE_DATA(oc, "step/assemblies/as1-oc-214.stp");
  QuietWarnings quiet;
  // The Pro/E file names every part 'SOLID': the plate is the part of largest volume.
  const auto plate = [](const Assembly& a) {
    const Part* best = &a.parts[0];
    for (const Part& p : a.parts) {
      if (p.mass.volume_mm3 > best->mass.volume_mm3) best = &p;
    }
    Eigen::Vector3d size = best->mesh.Bounds().sizes();
    std::sort(size.data(), size.data() + 3);
    return size;
  };
  const Eigen::Vector3d reference = plate(ImportCad(oc, Coarse()));
  ASSERT_TRUE(reference.isApprox(Eigen::Vector3d(20, 150, 180), 1e-3)) << reference.transpose();
  const Assembly as_declared = ImportCad(pe, Coarse());
  EXPECT_TRUE(plate(as_declared).isApprox(25.4 * reference, 1e-3))
      << plate(as_declared).transpose();
  const Assembly repaired = ImportCad(pe, Coarse("mm"));
  EXPECT_TRUE(plate(repaired).isApprox(reference, 1e-3)) << plate(repaired).transpose();
  EXPECT_EQ(repaired.length_unit, "mm (stated by the recipe, file declares INCH)");
}

TEST(ImportSharedData, EightStoredCopiesAreOnePartWithEightInstances) {
  CADSYNTH_REQUIRE_DATA(file, "step/assemblies/eight_cyl.stp");
  const Assembly a = ImportCad(file, Coarse());
  ASSERT_EQ(a.parts.size(), 1u);
  ASSERT_EQ(a.instances.size(), 8u);
  // The copies sit at (+-207.6, +-55.8, +-185): their centres survive the merge.
  for (const Instance& i : a.instances) {
    const Eigen::Vector3d c = a.parts[0].mesh.Bounds(i.world_from_model).center();
    EXPECT_NEAR(std::abs(c.x()), 207.6, 0.1);
    EXPECT_NEAR(std::abs(c.y()), 55.83, 0.1);
    EXPECT_NEAR(std::abs(c.z()), 185.0, 0.1);
  }
}

TEST(ImportSharedData, TessellatedOnlyFilePassesItsTrianglesThrough) {
  CADSYNTH_REQUIRE_DATA(file, "step/nist_pmi/nist_ftc_08_asme1_ap242-e1-tg.stp");
  const Assembly a = ImportCad(file, Coarse());
  EXPECT_EQ(a.format, "STEP (tessellated)");
  ASSERT_EQ(a.parts.size(), 1u);  // the supplemental-geometry plane is left out
  const Part& body = a.parts[0];
  EXPECT_EQ(body.name, "PartBody");
  // 273 COMPLEX_TRIANGULATED_FACEs of strips and fans: closed and consistently wound, so the
  // strip decoding and the winding by the file's normals are right.
  EXPECT_EQ(body.mesh.num_triangles(), 3368u);
  EXPECT_TRUE(body.watertight);
  EXPECT_GT(body.mass.volume_mm3, 0.0);
  EXPECT_TRUE(body.mesh.Bounds().sizes().isApprox(Eigen::Vector3d(311.6, 222.7, 48.26), 1e-3))
      << body.mesh.Bounds().sizes().transpose();
  EXPECT_TRUE(body.color.has_value());
}

TEST(Import, TessellatedStepWrittenByHand) {
  // One TRIANGULATED_FACE closing a tetrahedron, in inches, outward triangles, normals omitted.
  ScratchDir dir;
  std::ofstream(dir / "tet.stp") << R"(ISO-10303-21;
HEADER;
FILE_DESCRIPTION((''),'2;1');
FILE_NAME('tet','',(''),(''),'','','');
FILE_SCHEMA(('AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIM_LF'));
ENDSEC;
DATA;
#1=COORDINATES_LIST('',4,((0.,0.,0.),(1.,0.,0.),(0.,1.,0.),(0.,0.,1.)));
#2=TRIANGULATED_FACE('',#1,4,(),$,(),((1,3,2),(1,2,4),(2,3,4),(3,1,4)));
#3=TESSELLATED_SOLID('tet',(#2),$);
ENDSEC;
END-ISO-10303-21;
)";
  const Assembly a = internal::ReadStepTessellated(dir / "tet.stp", 25.4);
  ASSERT_EQ(a.parts.size(), 1u);
  EXPECT_EQ(a.parts[0].name, "tet");
  EXPECT_TRUE(a.parts[0].watertight);
  EXPECT_NEAR(a.parts[0].mass.volume_mm3, std::pow(25.4, 3) / 6.0, 1e-2);
  std::ofstream(dir / "bad.stp") << "ISO-10303-21;\nDATA;\n#1=TESSELLATED_SOLID('x',(#2),$);\n#2="
                                    "TRIANGULATED_FACE('',#9,3,(),$,(),((1,2,3)));\nENDSEC;\n";
  try {
    internal::ReadStepTessellated(dir / "bad.stp", 1.0);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              (dir / "bad.stp").string() +
                  ": #2 TRIANGULATED_FACE: its coordinates are not a COORDINATES_LIST");
  }
}

// Found by the libFuzzer harness (tools/fuzz/step_tessellated_fuzz.cpp): a 30-digit entity
// number ended the process (std::stol threw out_of_range), and lists nested without end would
// exhaust the stack. Both are one Error now.
TEST(Import, TessellatedReaderRefusesHugeNumbersAndDeepLists) {
  ScratchDir dir;
  std::ofstream(dir / "big.stp") << "ISO-10303-21;\nDATA;\n#1=TESSELLATED_SOLID('x',(#"
                                 << std::string(30, '9') << "),$);\nENDSEC;\n";
  try {
    internal::ReadStepTessellated(dir / "big.stp", 1.0);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("a number too large"), std::string::npos) << e.what();
  }
  std::ofstream(dir / "deep.stp") << "ISO-10303-21;\nDATA;\n#1=COORDINATES_LIST('',"
                                  << std::string(5000, '(') << std::string(5000, ')')
                                  << ");\n#2=TESSELLATED_SOLID('x',(#1),$);\nENDSEC;\n";
  try {
    internal::ReadStepTessellated(dir / "deep.stp", 1.0);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("nested more than 1000 deep"), std::string::npos)
        << e.what();
  }
}

TEST(ImportSharedData, ExternalReferencesResolveFromAnyFolder) {
  CADSYNTH_REQUIRE_DATA(file, "step/awkward/external_refs_s1-c5-214/s1-c5-214.stp");
  const Assembly a = ImportCad(std::filesystem::relative(file), Coarse());
  // 8 leaf files; FOOT_FRONT_000 and FOOT_BACK_000 hold the same shape, so 7 parts.
  EXPECT_EQ(a.parts.size(), 7u);
  EXPECT_EQ(a.instances.size(), 11u);
}

TEST(ImportSharedData, BinaryStlWithSolidHeaderAndColladaAgree) {
  CADSYNTH_REQUIRE_DATA(stl, "mesh/seed_speed_reducer/left_gear.STL");
  CADSYNTH_REQUIRE_DATA(dae, "mesh/seed_speed_reducer/left_gear.dae");
  QuietWarnings quiet;
  const Assembly a = ImportCad(stl, Coarse("m"));
  EXPECT_EQ(quiet.count(), 0);  // 25 mm in metres: plausible, no warning
  ASSERT_EQ(a.parts.size(), 1u);
  EXPECT_EQ(a.parts[0].mesh.num_triangles(), 18164u);
  EXPECT_EQ(a.format, "mesh (stl)");
  EXPECT_FALSE(a.parts[0].color.has_value());  // STL has no colours (not assimp's default grey)
  const Eigen::Vector3d size = a.parts[0].mesh.Bounds().sizes();
  EXPECT_NEAR(size.maxCoeff(), 25.09, 0.01);
  const Assembly b = ImportCad(dae, Coarse("m"));
  EXPECT_TRUE(b.parts[0].color.has_value());  // the Blender export's material
  EXPECT_TRUE(b.parts[0].mesh.Bounds().sizes().isApprox(size, 1e-3));
  // Without a unit the metre file is 0.025 mm: a warning says which unit would make sense.
  ImportCad(stl, Coarse());
  EXPECT_EQ(quiet.count(), 1);
}

TEST(ImportSharedData, NamesInALocalCodePageAreReadableWhenStated) {
  CADSYNTH_REQUIRE_DATA(file, "step/awkward/bug31670_russian.stp");
  QuietWarnings quiet;
  const Assembly guessed = ImportCad(file, Coarse());
  EXPECT_EQ(quiet.count(), 1);  // the raw CP1251 bytes are not UTF-8: say so
  EXPECT_EQ(guessed.name, "\u00d1\u00e1\u00ee\u00f0\u00ea\u00e01");  // Latin-1 reading of the bytes
  ImportOptions cyrillic = Coarse();
  cyrillic.encoding = "cp1251";
  const Assembly read = ImportCad(file, cyrillic);
  EXPECT_EQ(read.name, "\u0421\u0431\u043e\u0440\u043a\u04301");  // "Сборка1": assembly 1
  EXPECT_EQ(quiet.count(), 1);
  EXPECT_EQ(StepCodePage("Shift_JIS"), "SJIS");
  EXPECT_EQ(StepCodePage("klingon"), "");
}

TEST(ImportSharedData, EscapedUnicodeNamesDecode) {
  CADSYNTH_REQUIRE_DATA(file, "step/parts/spur_gear_10t_fusion360.step");
  const Assembly a = ImportCad(file, Coarse());
  EXPECT_EQ(a.name, "(\u672a\u4fdd\u5b58)");  // "(未保存)", written as \X2\ escapes
}

TEST(Import, BadFilesGiveClearErrors) {
  ScratchDir dir;
  EXPECT_EQ(ErrorOf(dir / "missing.step"), (dir / "missing.step").string() + ": no such file");
  EXPECT_EQ(ErrorOf(dir.path()), dir.path().string() + ": is a folder, not a file");
  std::ofstream(dir / "empty.stl").close();
  EXPECT_EQ(ErrorOf(dir / "empty.stl"), (dir / "empty.stl").string() + ": file is empty");
  {
    std::ofstream garbage(dir / "garbage.stl", std::ios::binary);
    for (int i = 0; i < 1000; ++i) garbage.put(static_cast<char>((i * 7919) % 251));
  }
  EXPECT_EQ(
      ErrorOf(dir / "garbage.stl")
          .rfind((dir / "garbage.stl").string() + ": truncated binary STL: its header says", 0),
      0u)
      << ErrorOf(dir / "garbage.stl");
  std::ofstream(dir / "notes.xyz") << "hello\n";
  EXPECT_NE(ErrorOf(dir / "notes.xyz").find("unknown kind of file"), std::string::npos);
  std::ofstream(dir / "noext") << "ISO-10303-21;\nHEADER;\n";
  EXPECT_EQ(DetectFormat(dir / "noext"), CadFormat::kStep);
  ImportOptions bad_unit = Coarse("furlong");
  EXPECT_NE(ErrorOf(dir / "noext", bad_unit).find("unknown length unit 'furlong'"),
            std::string::npos);
}

TEST(Import, TruncatedRealFileIsAnError) {
  CADSYNTH_REQUIRE_DATA(file, "step/parts/xr1-tc-blt.stp");
  ScratchDir dir;
  std::ifstream in(file, std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(dir / "half.stp", std::ios::binary) << text.substr(0, text.size() / 2);
  const std::string message = ErrorOf(dir / "half.stp");
  EXPECT_EQ(message.rfind((dir / "half.stp").string() + ": ", 0), 0u) << message;
}

TEST(Import, ObjMeshWithUnitAndMassProperties) {
  ScratchDir dir;
  // A closed unit cube in metres, as an OBJ with outward quads.
  std::ofstream(dir / "cube.obj")
      << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
         "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
  QuietWarnings quiet;
  const Assembly a = ImportCad(dir / "cube.obj", Coarse("cm"));
  ASSERT_EQ(a.parts.size(), 1u);
  const Part& p = a.parts[0];
  EXPECT_EQ(p.mesh.num_triangles(), 12u);
  EXPECT_TRUE(p.watertight);
  EXPECT_NEAR(p.mass.volume_mm3, 1000.0, 1e-3);  // 1 cm^3
  EXPECT_TRUE(p.mesh.Bounds().sizes().isApprox(Eigen::Vector3d(10, 10, 10), 1e-6));
  EXPECT_TRUE(
      a.instances[0].world_from_model.translation().isApprox(Eigen::Vector3d(5, 5, 5), 1e-6));
  EXPECT_EQ(quiet.count(), 0);
}

// Library wording stays out of errors: OpenCASCADE's exceptions whose message is a class name, and
// assimp's phrases, become what they mean for the file.
TEST(Import, LibraryFailuresAreSaidInPlainWords) {
  EXPECT_EQ(internal::PlainFailure(Standard_OutOfRange("NCollection_Sequence::Value")),
            "a value out of range (a damaged index or count?)");
  EXPECT_EQ(internal::PlainFailure(Standard_DomainError("BRep_Tool::Curve")),
            "a curve or surface that cannot be built from its numbers");
  EXPECT_EQ(internal::PlainFailure(Standard_DomainError("the surface is not closed")),
            "the surface is not closed");
  EXPECT_EQ(internal::PlainAssimpError("all meshes are orphaned", "a.dae"),
            "its meshes are not placed in its scene (no node uses them)");
  // The file's path is shortened to its name, also when the two are the same (it looped).
  EXPECT_EQ(internal::PlainAssimpError("OBJ: bad face in part.obj, part.obj", "part.obj"),
            "bad face in part.obj, part.obj");
  EXPECT_EQ(internal::PlainAssimpError("XML: cannot parse /data/x/part.dae", "/data/x/part.dae"),
            "cannot parse part.dae");
  ScratchDir dir;
  std::ofstream(dir / "lines.obj") << "v 0 0 0\nv 1 0 0\nl 1 2\n";
  EXPECT_EQ(ErrorOf(dir / "lines.obj"),
            (dir / "lines.obj").string() +
                ": not a readable mesh: the file holds no triangles (only points or lines?)");
  std::ofstream(dir / "noise.3mf") << std::string(3000, 'x');
  EXPECT_EQ(ErrorOf(dir / "noise.3mf"),
            (dir / "noise.3mf").string() +
                ": not a 3MF file (3MF files are ZIP archives with files in them; this is none)");
}

// A BREP file cut inside its shape list made OpenCASCADE loop for ever; it is refused first, and
// the whole file still reads.
TEST(Import, BrepCutInsideItsShapeListIsTruncated) {
  ScratchDir dir;
  BRepTools::Write(OcctShape(MakeBox(30, 20, 10)), (dir / "box.brep").string().c_str());
  const std::string text = testing::ReadFile(dir / "box.brep");
  EXPECT_EQ(ImportCad(dir / "box.brep", Coarse()).parts.size(), 1u);
  std::ofstream(dir / "cut.brep") << text.substr(0, text.rfind('*'));
  EXPECT_NE(ErrorOf(dir / "cut.brep").find("cut.brep: truncated: the file declares"),
            std::string::npos)
      << ErrorOf(dir / "cut.brep");
  std::ofstream(dir / "rootless.brep") << text.substr(0, text.rfind('*') + 2);
  EXPECT_NE(ErrorOf(dir / "rootless.brep").find("ends before naming its root shape"),
            std::string::npos)
      << ErrorOf(dir / "rootless.brep");
}

TEST(Import, IgesWrittenByOpenCascadeReadsBackInMillimetres) {
  ScratchDir dir;
  const Shape box = MakeBox(25.4, 50.8, 76.2);  // 1 x 2 x 3 inches
  for (const char* unit : {"MM", "IN"}) {
    const std::filesystem::path file = dir / (std::string("box_") + unit + ".igs");
    IGESControl_Writer writer(unit, 0);
    ASSERT_TRUE(writer.AddShape(OcctShape(box)));
    writer.ComputeModel();
    ASSERT_TRUE(writer.Write(file.string().c_str()));
    const Assembly a = ImportCad(file, Coarse());
    EXPECT_EQ(a.format, "IGES");
    ASSERT_EQ(a.parts.size(), 1u) << unit;
    EXPECT_TRUE(a.parts[0].mesh.Bounds().sizes().isApprox(Eigen::Vector3d(25.4, 50.8, 76.2), 1e-4))
        << unit << ": " << a.parts[0].mesh.Bounds().sizes().transpose();
    EXPECT_NEAR(a.parts[0].mass.volume_mm3, 25.4 * 50.8 * 76.2, 1e-2);
  }
}

TEST(ImportSharedData, FaceColoursGiveThePartTheColourOfMostOfItsArea) {
  CADSYNTH_REQUIRE_DATA(file, "step/parts/io1-cm-214.stp");  // colours on faces only
  const Assembly a = ImportCad(file, Coarse());
  ASSERT_EQ(a.parts.size(), 1u);
  ASSERT_TRUE(a.parts[0].color.has_value());
  EXPECT_TRUE(a.parts[0].color->isApprox(Eigen::Vector3f(1, 1, 0), 1e-3f))
      << a.parts[0].color->transpose();
}

TEST(Import, BrepFileIsOnePart) {
  CADSYNTH_REQUIRE_DATA(file, "brep/occt_engine/CrankArm.brep");
  const Assembly a = ImportCad(file, Coarse());
  ASSERT_EQ(a.parts.size(), 1u);
  EXPECT_EQ(a.format, "BREP");
  EXPECT_EQ(a.parts[0].name, "CrankArm");
  EXPECT_GT(a.parts[0].mass.volume_mm3, 0.0);
}

}  // namespace
}  // namespace cadsynth
