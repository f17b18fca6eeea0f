#include "variants/standard_parts.h"

#include <cmath>
#include <sstream>

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakePolygon.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <BRepPrimAPI_MakeRevol.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <BRep_Builder.hxx>
#include <Standard_Failure.hxx>
#include <TopoDS_Compound.hxx>
#include <gp_Ax2.hxx>
#include <gp_Circ.hxx>

#include "cad/core/error.h"
#include "cad/occt_shape.h"
#include "variants/occt_boolean.h"

namespace cadsynth {
namespace {

// ISO 4017 (s, k), ISO 4032 (m), ISO 7089 (d1, d2, h).
const std::vector<MetricSize>& MetricTable() {
  static const std::vector<MetricSize> table = {
      {"M3", 3, 5.5, 2.0, 2.4, 3.2, 7, 0.5},    {"M4", 4, 7, 2.8, 3.2, 4.3, 9, 0.8},
      {"M5", 5, 8, 3.5, 4.7, 5.3, 10, 1.0},     {"M6", 6, 10, 4.0, 5.2, 6.4, 12, 1.6},
      {"M8", 8, 13, 5.3, 6.8, 8.4, 16, 1.6},    {"M10", 10, 16, 6.4, 8.4, 10.5, 20, 2.0},
      {"M12", 12, 18, 7.5, 10.8, 13, 24, 2.5},  {"M14", 14, 21, 8.8, 12.8, 15, 28, 2.5},
      {"M16", 16, 24, 10.0, 14.8, 17, 30, 3.0}, {"M20", 20, 30, 12.5, 18.0, 21, 37, 3.0},
      {"M24", 24, 36, 15.0, 21.5, 25, 44, 4.0}};
  return table;
}

// ISO 7379: shoulder d, thread d, thread length, head d, head k, socket s.
const std::vector<ShoulderSize>& ShoulderTable() {
  static const std::vector<ShoulderSize> table = {
      {6, 5, 9.5, 10, 4.5, 3}, {8, 6, 11, 13, 5.5, 4},  {10, 8, 13, 16, 7, 5},
      {12, 10, 16, 18, 8, 6},  {16, 12, 18, 24, 10, 8}, {20, 16, 22, 30, 14, 10}};
  return table;
}

void Require(bool ok, const std::string& what) {
  if (!ok) throw Error(what);
}

TopoDS_Wire Circle(double radius, double x = 0, double y = 0) {
  return BRepBuilderAPI_MakeWire(
             BRepBuilderAPI_MakeEdge(gp_Circ(gp_Ax2(gp_Pnt(x, y, 0), gp_Dir(0, 0, 1)), radius)))
      .Wire();
}

// Regular hexagon with width `s` across flats (flats parallel to x), centred on the origin.
TopoDS_Wire Hexagon(double s) {
  BRepBuilderAPI_MakePolygon polygon;
  const double r = s / std::sqrt(3.0);
  for (int k = 0; k < 6; ++k) {
    const double a = k * M_PI / 3;  // corners on the x axis, flats parallel to it
    polygon.Add(gp_Pnt(r * std::cos(a), r * std::sin(a), 0));
  }
  polygon.Close();
  return polygon.Wire();
}

TopoDS_Shape Extrude(const TopoDS_Wire& outer, std::vector<TopoDS_Wire> holes, double height,
                     double z0 = 0) {
  BRepBuilderAPI_MakeFace face(outer, true);
  for (TopoDS_Wire& hole : holes) {
    hole.Reverse();
    face.Add(hole);
  }
  TopoDS_Shape prism = BRepPrimAPI_MakePrism(face.Face(), gp_Vec(0, 0, height)).Shape();
  if (z0 != 0) {
    gp_Trsf lift;
    lift.SetTranslation(gp_Vec(0, 0, z0));
    prism.Move(TopLoc_Location(lift));
  }
  return prism;
}

// A solid of revolution about z from a closed (r, z) polyline.
TopoDS_Shape Revolve(const std::vector<std::pair<double, double>>& profile) {
  BRepBuilderAPI_MakePolygon polygon;
  for (const auto& [r, z] : profile) polygon.Add(gp_Pnt(r, 0, z));
  polygon.Close();
  const TopoDS_Face face = BRepBuilderAPI_MakeFace(polygon.Wire(), true);
  return BRepPrimAPI_MakeRevol(face, gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 2 * M_PI).Shape();
}

template <typename Build>
Component Guarded(const std::string& what, Build&& build) {
  try {
    return build();
  } catch (const Standard_Failure& failure) {
    throw Error(what + ": OpenCASCADE failed: " + failure.GetMessageString());
  }
}

void Positive(double value, const std::string& what) {
  std::ostringstream out;
  out << what << " must be positive (got " << value << ")";
  Require(value > 0 && std::isfinite(value), out.str());
}

}  // namespace

const MetricSize& IsoMetric(const std::string& name) {
  for (const MetricSize& size : MetricTable()) {
    if (size.name == name) return size;
  }
  std::string known;
  for (const MetricSize& size : MetricTable()) known += (known.empty() ? "" : ", ") + size.name;
  throw Error("unknown metric size '" + name + "' (known: " + known + ")");
}

std::vector<std::string> IsoMetricSizes() {
  std::vector<std::string> names;
  for (const MetricSize& size : MetricTable()) names.push_back(size.name);
  return names;
}

const ShoulderSize& IsoShoulder(double shoulder_d) {
  for (const ShoulderSize& size : ShoulderTable()) {
    if (std::abs(size.shoulder_d - shoulder_d) < 1e-9) return size;
  }
  std::ostringstream out;
  out << "no ISO 7379 shoulder bolt with a " << shoulder_d
      << " mm shoulder (known: 6, 8, 10, 12, 16, 20)";
  throw Error(out.str());
}

Component MakeRoundPeg(double diameter, double length) {
  Positive(diameter, "peg diameter");
  Positive(length, "peg length");
  return Guarded("round peg", [&] {
    return Component{"round_peg",
                     WrapShape(BRepPrimAPI_MakeCylinder(0.5 * diameter, length).Shape()),
                     Symmetries::Revolution(true, 0.5 * length)};
  });
}

Component MakeSquarePeg(double side, double length) {
  Positive(side, "peg side");
  Positive(length, "peg length");
  return Guarded("square peg", [&] {
    const TopoDS_Shape box = BRepPrimAPI_MakeBox(gp_Pnt(-0.5 * side, -0.5 * side, 0),
                                                 gp_Pnt(0.5 * side, 0.5 * side, length))
                                 .Shape();
    return Component{"square_peg", WrapShape(box), Symmetries::Cyclic(4, true, 0.5 * length)};
  });
}

Component MakeCasing(double length, double width, double height, double wall,
                     double seat_diameter) {
  Positive(length, "casing length");
  Positive(width, "casing width");
  Positive(height, "casing height");
  Positive(wall, "casing wall");
  Require(2 * wall < width && 2 * wall < length && wall < height,
          "a casing's walls leave no room inside it (2 x wall must be less than its length and "
          "width, wall less than its height)");
  Require(
      seat_diameter >= 0 && seat_diameter < width - 2 * wall && 0.5 * seat_diameter < height - wall,
      "a casing's bearing seat must be narrower than its inside (width - 2 x wall) and "
      "shallower than its inside's depth (height - wall)");
  return Guarded("casing", [&] {
    const TopoDS_Shape outer = BRepPrimAPI_MakeBox(gp_Pnt(-0.5 * length, -0.5 * width, 0),
                                                   gp_Pnt(0.5 * length, 0.5 * width, height))
                                   .Shape();
    const TopoDS_Shape pocket =
        BRepPrimAPI_MakeBox(gp_Pnt(-0.5 * length + wall, -0.5 * width + wall, wall),
                            gp_Pnt(0.5 * length - wall, 0.5 * width - wall, height + 1.0))
            .Shape();
    TopoDS_Shape body = RunBoolean(BRepAlgoAPI_Cut(outer, pocket), "hollow the casing");
    if (seat_diameter > 0) {
      // One cylinder along x through both end walls, its axis on the casing's top edge.
      const TopoDS_Shape seat =
          BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(-0.5 * length - 1.0, 0, height), gp_Dir(1, 0, 0)),
                                   0.5 * seat_diameter, length + 2.0)
              .Shape();
      body = RunBoolean(BRepAlgoAPI_Cut(body, seat), "cut the casing's bearing seats");
    }
    // A half turn about z maps it onto itself; it has no flip (its top is open).
    return Component{"casing", WrapShape(body), Symmetries::Cyclic(2, false)};
  });
}

Component MakeFaceplate(double width, double height, double thickness, int rows, int columns,
                        double hole_diameter, double margin) {
  Positive(width, "faceplate width");
  Positive(height, "faceplate height");
  Positive(thickness, "faceplate thickness");
  Require(rows >= 1 && columns >= 1, "a faceplate needs at least one row and one column of holes");
  Positive(hole_diameter, "hole diameter");
  const double span_x = width - 2 * margin, span_y = height - 2 * margin;
  const double pitch_x = columns > 1 ? span_x / (columns - 1) : 0,
               pitch_y = rows > 1 ? span_y / (rows - 1) : 0;
  std::ostringstream why;
  why << "holes of " << hole_diameter << " mm do not fit: " << rows << " x " << columns
      << " holes need more than " << width << " x " << height << " mm with a " << margin
      << " mm margin";
  Require(margin > 0.5 * hole_diameter && span_x >= 0 && span_y >= 0 &&
              (columns == 1 || pitch_x > hole_diameter) && (rows == 1 || pitch_y > hole_diameter),
          why.str());
  return Guarded("faceplate", [&] {
    BRepBuilderAPI_MakePolygon outline;
    for (const auto& [x, y] : {std::pair{-0.5, -0.5}, {0.5, -0.5}, {0.5, 0.5}, {-0.5, 0.5}}) {
      outline.Add(gp_Pnt(x * width, y * height, 0));
    }
    outline.Close();
    std::vector<TopoDS_Wire> holes;
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < columns; ++c) {
        const double x = columns > 1 ? -0.5 * span_x + c * pitch_x : 0.0;
        const double y = rows > 1 ? -0.5 * span_y + r * pitch_y : 0.0;
        holes.push_back(Circle(0.5 * hole_diameter, x, y));
      }
    }
    // A centred, evenly spaced grid keeps the plate's symmetries (4-fold when square).
    const bool square = std::abs(width - height) < 1e-9 && rows == columns;
    Symmetries symmetries = square ? Symmetries::Cyclic(4, true, 0.5 * thickness)
                                   : Symmetries::Cyclic(2, true, 0.5 * thickness);
    return Component{"faceplate", WrapShape(Extrude(outline.Wire(), holes, thickness)), symmetries};
  });
}

Component MakeSteppedShaft(const std::vector<std::pair<double, double>>& sections) {
  Require(!sections.empty(), "a stepped shaft needs at least one section");
  std::vector<std::pair<double, double>> profile = {{0, 0}};
  double z = 0;
  for (const auto& [d, l] : sections) {
    Positive(d, "shaft section diameter");
    Positive(l, "shaft section length");
    profile.emplace_back(0.5 * d, z);
    z += l;
    profile.emplace_back(0.5 * d, z);
  }
  profile.emplace_back(0, z);
  bool palindrome = true;
  for (size_t i = 0; i < sections.size(); ++i) {
    const auto& a = sections[i];
    const auto& b = sections[sections.size() - 1 - i];
    palindrome =
        palindrome && std::abs(a.first - b.first) < 1e-9 && std::abs(a.second - b.second) < 1e-9;
  }
  return Guarded("stepped shaft", [&] {
    return Component{"stepped_shaft", WrapShape(Revolve(profile)),
                     Symmetries::Revolution(palindrome, 0.5 * z)};
  });
}

Component MakeShoulderBolt(double shoulder_d, double shoulder_length) {
  const ShoulderSize& size = IsoShoulder(shoulder_d);
  Positive(shoulder_length, "shoulder length");
  return Guarded("shoulder bolt", [&] {
    const double k = size.head_k, lt = size.thread_length;
    const TopoDS_Shape body = Revolve({{0, 0},
                                       {0.5 * size.head_d, 0},
                                       {0.5 * size.head_d, k},
                                       {0.5 * size.shoulder_d, k},
                                       {0.5 * size.shoulder_d, k + shoulder_length},
                                       {0.5 * size.thread_d, k + shoulder_length},
                                       {0.5 * size.thread_d, k + shoulder_length + lt},
                                       {0, k + shoulder_length + lt}});
    const TopoDS_Shape socket = Extrude(Hexagon(size.socket_s), {}, 0.6 * k + 1.0, -1.0);
    return Component{"shoulder_bolt",
                     WrapShape(RunBoolean(BRepAlgoAPI_Cut(body, socket), "cut the socket")),
                     Symmetries::Cyclic(6, false)};
  });
}

Component MakeHexBolt(const std::string& name, double length) {
  const MetricSize& size = IsoMetric(name);
  Positive(length, "bolt length");
  return Guarded("hex bolt", [&] {
    const TopoDS_Shape head = Extrude(Hexagon(size.s), {}, size.k);
    const TopoDS_Shape shank =
        BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, size.k), gp_Dir(0, 0, 1)), 0.5 * size.d,
                                 length)
            .Shape();
    return Component{
        "hex_bolt_" + size.name,
        WrapShape(RunBoolean(BRepAlgoAPI_Fuse(head, shank), "fuse the head and the shank")),
        Symmetries::Cyclic(6, false)};
  });
}

Component MakeHexNut(const std::string& name) {
  const MetricSize& size = IsoMetric(name);
  return Guarded("hex nut", [&] {
    return Component{"hex_nut_" + size.name,
                     WrapShape(Extrude(Hexagon(size.s), {Circle(0.5 * size.d)}, size.m)),
                     Symmetries::Cyclic(6, true, 0.5 * size.m)};
  });
}

Component MakeWasher(const std::string& name) {
  const MetricSize& size = IsoMetric(name);
  return Guarded("washer", [&] {
    return Component{"washer_" + size.name,
                     WrapShape(Extrude(Circle(0.5 * size.washer_outer),
                                       {Circle(0.5 * size.washer_inner)}, size.washer_thickness)),
                     Symmetries::Revolution(true, 0.5 * size.washer_thickness)};
  });
}

Component MakeBallBearing(double bore, double outer, double width) {
  Positive(bore, "bearing bore");
  Positive(width, "bearing width");
  std::ostringstream why;
  why << "bearing outer diameter " << outer << " mm must exceed the bore " << bore
      << " mm by at least 6 mm";
  Require(outer > bore + 6, why.str());
  return Guarded("ball bearing", [&] {
    const double pitch = 0.25 * (bore + outer);                       // pitch circle radius
    const double ball = std::min(0.3 * (outer - bore), 0.8 * width);  // ball diameter
    const int balls = std::max(3, static_cast<int>(std::floor(M_PI * 2 * pitch / (1.2 * ball))));
    const double groove = 0.52 * ball;  // groove radius
    const double gap = 0.15 * ball;     // rings stop short of the pitch circle
    const TopoDS_Shape torus = [&] {
      TopoDS_Shape t =
          BRepPrimAPI_MakeTorus(gp_Ax2(gp_Pnt(0, 0, 0.5 * width), gp_Dir(0, 0, 1)), pitch, groove)
              .Shape();
      return t;
    }();
    const TopoDS_Shape inner = RunBoolean(
        BRepAlgoAPI_Cut(
            Revolve({{0.5 * bore, 0}, {pitch - gap, 0}, {pitch - gap, width}, {0.5 * bore, width}}),
            torus),
        "cut the inner race's groove");
    const TopoDS_Shape outer_ring = RunBoolean(
        BRepAlgoAPI_Cut(
            Revolve(
                {{pitch + gap, 0}, {0.5 * outer, 0}, {0.5 * outer, width}, {pitch + gap, width}}),
            torus),
        "cut the outer race's groove");
    BRep_Builder builder;
    TopoDS_Compound all;
    builder.MakeCompound(all);
    builder.Add(all, inner);
    builder.Add(all, outer_ring);
    for (int i = 0; i < balls; ++i) {
      const double a = 2 * M_PI * i / balls;
      builder.Add(
          all, BRepPrimAPI_MakeSphere(gp_Pnt(pitch * std::cos(a), pitch * std::sin(a), 0.5 * width),
                                      0.5 * ball)
                   .Shape());
    }
    return Component{"ball_bearing", WrapShape(all), Symmetries::Cyclic(balls, true, 0.5 * width)};
  });
}

}  // namespace cadsynth
