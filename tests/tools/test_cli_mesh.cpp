// `quadrix mesh`: every writer read back by core/io, the measured error in the report, exit codes.
#include <gtest/gtest.h>

#include "tests/support.h"
#include "tests/tools/cli_support.h"

#include <cmath>
#include <fstream>

#include <nlohmann/json.hpp>

#include "core/bounds.h"
#include "core/mesh_io.h"
#include "core/model_io.h"

using namespace quadrix;
using test_support::CmdResult;
using test_support::q;
using test_support::quadrix_run;
using test_support::read_json;

namespace {
}  // namespace

class CliMesh : public test_support::TempDir {};

TEST_F(CliMesh, EveryFormatReadsBackWithinTheReportedError) {
  const auto model = dir_ / "s.qxm";
  ASSERT_EQ(quadrix_run("synth sphere -o " + q(model)).code, 0);
  std::size_t triangles = 0;
  for (const char* ext : {".ply", ".obj", ".off", ".stl"}) {
    const auto out = dir_ / (std::string("s") + ext), report = dir_ / (std::string("r") + ext + ".json");
    const CmdResult r = quadrix_run("mesh " + q(model) + " -o " + q(out) + " --max-error-abs 1e-3 --report " + q(report));
    ASSERT_EQ(r.code, 0) << ext << ": " << r.out;
    EXPECT_NE(r.out.find("triangles"), std::string::npos) << "no summary line: " << r.out;
    const auto j = read_json(report)["mesh"];
    EXPECT_TRUE(j["within_bound"].get<bool>());
    EXPECT_LE(j["max_error"].get<double>(), 1e-3);
    EXPECT_EQ(j["open_edges"].get<int>(), 0);
    // Checked on the positions as written (STL's float32 included): none cross.
    EXPECT_EQ(j["self_intersecting_pairs"].get<std::size_t>(), 0u) << ext;
    EXPECT_NE(r.out.find("closed (no open edges), no self-intersections"), std::string::npos) << r.out;
    EXPECT_EQ(j["fin_rounds"].get<int>(), 0);  // a sphere glyph: nothing open
    EXPECT_EQ(j["fin_triangles"].get<std::size_t>(), 0u);
    const PolygonMesh m = read_mesh(out);
    if (!triangles) triangles = m.face_count();
    EXPECT_EQ(m.face_count(), triangles) << ext;
    EXPECT_EQ(m.face_count(), j["triangles"].get<std::size_t>()) << ext;
    // The unit sphere glyph: every vertex read back lies on it (STL stores float32).
    const double tol = std::string(ext) == ".stl" ? 1e-6 : 1e-12;
    for (const auto& v : m.vertices) ASSERT_NEAR(v.norm(), 1.0, tol) << ext;
    // The glyph's colour carried over, and read back (OFF and OBJ read grey); STL holds none and
    // claims none (its summary said "with colours").
    if (std::string(ext) != ".stl") {
      ASSERT_EQ(m.colours.size(), m.vertices.size()) << ext;
      EXPECT_TRUE(j["colours"].get<bool>());
    } else {
      EXPECT_TRUE(m.colours.empty());
      EXPECT_FALSE(j["colours"].get<bool>());
      EXPECT_NE(r.out.find("STL holds no colours"), std::string::npos) << r.out;
      EXPECT_EQ(r.out.find("with colours"), std::string::npos) << r.out;
    }
    // The sphere's own normals, except in STL (face normals only; it claimed them).
    EXPECT_EQ(j["normals"].get<bool>(), std::string(ext) != ".stl") << ext;
    if (std::string(ext) != ".stl") {
      ASSERT_EQ(m.normals.size(), m.vertices.size()) << ext;
      for (std::size_t v = 0; v < m.vertices.size(); ++v) ASSERT_NEAR(m.normals[v].dot(m.vertices[v].normalized()), 1.0, 1e-6) << ext;
    }
  }
}

TEST_F(CliMesh, AMoleculeIsMeshedAndAMeshOrACloudRefusedSayingWhatToDo) {
  const auto pdb = std::filesystem::path(QUADRIX_DATASETS) / "molecules" / "4lfq.pdb";
  if (!std::filesystem::exists(pdb)) GTEST_SKIP() << pdb << " not found";
  const auto report = dir_ / "m.json";
  CmdResult r = quadrix_run("mesh " + q(pdb) + " --style spacefill -o " + q(dir_ / "m.ply") + " --report " + q(report));
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = read_json(report)["mesh"];
  EXPECT_EQ(j["input"].get<std::string>(), "molecule");
  EXPECT_GT(j["triangles"].get<std::size_t>(), 1000u);
  EXPECT_NE(r.out.find("closed (no open edges"), std::string::npos) << r.out;
  // The atoms' union: one closed surface, no triangles crossing.
  EXPECT_TRUE(j["glyph_union"].get<bool>());
  EXPECT_EQ(j["self_intersecting_pairs"].get<std::size_t>(), 0u);
  EXPECT_NE(r.out.find("no self-intersections"), std::string::npos) << r.out;
  EXPECT_EQ(read_mesh(dir_ / "m.ply").face_count(), j["triangles"].get<std::size_t>());
  // --union off: each atom its own closed sphere, so overlapping atoms' triangles cross: counted,
  // named in the summary (what a slicer or a boolean operation would refuse).
  const auto apart = dir_ / "apart.json";
  r = quadrix_run("mesh " + q(pdb) + " --style spacefill --union off -o " + q(dir_ / "a.ply") + " --report " + q(apart));
  ASSERT_EQ(r.code, 0) << r.out;
  const auto ja = read_json(apart)["mesh"];
  EXPECT_FALSE(ja["glyph_union"].get<bool>());
  EXPECT_GT(ja["self_intersecting_pairs"].get<std::size_t>(), 1000u);
  EXPECT_FALSE(ja["self_intersecting_examples"].empty());
  EXPECT_NE(r.out.find("pairs of triangles crossing"), std::string::npos) << r.out;
  // Balls and sticks (the default style): atoms and bonds' tubes as one closed surface too (they
  // were meshed glyph by glyph, 63,964 pairs crossing).
  const auto sticks = dir_ / "bs.json";
  r = quadrix_run("mesh " + q(pdb) + " -o " + q(dir_ / "bs.ply") + " --report " + q(sticks));
  ASSERT_EQ(r.code, 0) << r.out;
  const auto jb = read_json(sticks)["mesh"];
  EXPECT_TRUE(jb["glyph_union"].get<bool>());
  EXPECT_EQ(jb["glyph_unions_failed"].get<std::size_t>(), 0u);
  EXPECT_EQ(jb["self_intersecting_pairs"].get<std::size_t>(), 0u);
  EXPECT_EQ(jb["degenerate_triangles"].get<std::size_t>(), 0u);
  EXPECT_EQ(jb["open_edges"].get<std::size_t>(), 0u);
  EXPECT_TRUE(jb["within_bound"].get<bool>());
  // A mesh: "a triangle mesh already" (it read "bad magic: not a PLY file"), exit 3, nothing written.
  r = quadrix_run("mesh " + q(dir_ / "m.ply") + " -o " + q(dir_ / "again.ply"));
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("a triangle mesh already"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "again.ply"));
  std::ofstream(dir_ / "p.xyz") << "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
  r = quadrix_run("mesh " + q(dir_ / "p.xyz") + " -o " + q(dir_ / "p.ply"));
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("fit it first"), std::string::npos) << r.out;
  // --style belongs to molecules.
  const auto model = dir_ / "s.qxm";
  ASSERT_EQ(quadrix_run("synth sphere -o " + q(model)).code, 0);
  EXPECT_EQ(quadrix_run("mesh " + q(model) + " --style licorice -o " + q(dir_ / "s.ply")).code, 2);
}

TEST_F(CliMesh, UnknownExtensionIsAUsageError) {
  const auto model = dir_ / "s.qxm";
  ASSERT_EQ(quadrix_run("synth sphere -o " + q(model)).code, 0);
  const CmdResult r = quadrix_run("mesh " + q(model) + " -o " + q(dir_ / "s.xyz"));
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "s.xyz"));
}

TEST_F(CliMesh, OutsideTheBoundWritesTheMeshAndExitsSeven) {
  const auto model = dir_ / "h.qxm", out = dir_ / "h.obj";
  ASSERT_EQ(quadrix_run("synth hyperboloid1 --resolution 4 -o " + q(model)).code, 0);
  const CmdResult r = quadrix_run("mesh " + q(model) + " -o " + q(out) + " --max-error-abs 1e-5 --max-refinements 0");
  EXPECT_EQ(r.code, 7) << r.out;
  EXPECT_TRUE(std::filesystem::exists(out));
  EXPECT_EQ(quadrix_run("mesh " + q(model) + " -o " + q(out) + " --max-error-abs 1e-5 --max-refinements 0 --allow-exceed --quiet").code, 0);
  // The report says why too (its error was null).
  const auto report = dir_ / "h.json";
  ASSERT_EQ(quadrix_run("mesh " + q(model) + " -o " + q(out) + " --max-error-abs 1e-5 --max-refinements 0 --quiet --report " + q(report)).code, 7);
  const auto j = read_json(report);
  EXPECT_EQ(j["exit_code"].get<int>(), 7);
  ASSERT_TRUE(j["error"].is_string()) << j.dump();
  EXPECT_NE(j["error"].get<std::string>().find("outside the bound"), std::string::npos) << j.dump();
}

// Implicit surfaces mesh too (they wrote 0 triangles, "max error inf", and exit 7): marching
// tetrahedra on S's sign over the bounds, crossings bisected onto S = 0. A torus inside its
// bounds comes out closed, within the bound, its vertices on the surface; cut by its bounds
// (z ≤ 0.1), open along the cut and nothing outside the bounds.
TEST_F(CliMesh, ImplicitSurfacesMeshOnTheirZeroSetWithinTheBound) {
  const auto write_implicit = [&](const char* name, const std::string& expression, double max_z) {
    const auto path = dir_ / name;
    std::ofstream out(path);
    out << "ply\nformat ascii 1.0\ncomment quadrix-format 2\nelement implicit 1\n"
           "property list uint uchar expression\nproperty list uchar double parameters\n"
           "property double min_x\nproperty double min_y\nproperty double min_z\n"
           "property double max_x\nproperty double max_y\nproperty double max_z\nend_header\n"
        << expression.size();
    for (const unsigned char ch : expression) out << ' ' << int(ch);
    out << " 0 -1.5 -1.5 -0.5 1.5 1.5 " << max_z << "\n";
    return path;
  };
  // (x² + y² + z² + R² − r²)² − 4R²(x² + y²), R = 1, r = 0.3.
  const std::string torus = "(x^2+y^2+z^2+0.91)^2-4*(x^2+y^2)";
  const auto torus_value = [](const Eigen::Vector3d& p) {
    const double s = p.squaredNorm() + 0.91;
    return s * s - 4 * (p.x() * p.x() + p.y() * p.y());
  };
  for (const double max_z : {0.5, 0.1}) {
    const auto model = write_implicit(max_z == 0.5 ? "t.qxm" : "cut.qxm", torus, max_z);
    const auto out = dir_ / "t.ply", report = dir_ / "t.json";
    const CmdResult r = quadrix_run("mesh " + q(model) + " -o " + q(out) + " --report " + q(report));
    ASSERT_EQ(r.code, 0) << r.out;
    const auto j = read_json(report)["mesh"];
    EXPECT_TRUE(j["within_bound"].get<bool>());
    EXPECT_GT(j["surface_to_mesh"]["samples"].get<std::size_t>(), 1000u);
    const PolygonMesh m = read_mesh(out);
    ASSERT_GT(m.face_count(), 1000u);
    for (const auto& v : m.vertices) {
      // On the torus: |S| / |∇S| (|∇S| ≈ 4R·r·2 = 2.4 near it) far below the bound.
      ASSERT_LT(std::abs(torus_value(v)), 1e-9) << v.transpose();
      ASSERT_LE(v.z(), max_z + 1e-12);
    }
    if (max_z == 0.5)
      EXPECT_EQ(j["open_edges"].get<int>(), 0);
    else
      EXPECT_GT(j["open_edges"].get<int>(), 0);
  }
}

// A SLIM fit is meshed at its own E by default where that is above 1e-3 of the diagonal (its
// blend steps by up to a few E between sheets: the torus quads fitted at 1e-2 and meshed at 1e-3
// ended 5.6 bounds off with open edges, exit 7); --max-error still sets the bound.
TEST_F(CliMesh, AFitIsMeshedAtItsOwnErrorUnlessToldOtherwise) {
  std::string xyz;
  for (int i = 0; i < 2000; ++i) {
    const double t = std::acos(1 - 2 * (i + 0.5) / 2000), p = i * 2.399963229728653;
    xyz += std::to_string(std::sin(t) * std::cos(p)) + " " + std::to_string(std::sin(t) * std::sin(p)) + " " +
           std::to_string(std::cos(t)) + "\n";
  }
  const auto points = dir_ / "p.xyz", model = dir_ / "f.qxm";
  { std::ofstream(points) << xyz; }
  ASSERT_EQ(quadrix_run("fit " + q(points) + " -o " + q(model) + " --max-error 0.01").code, 0);
  const double fit_e = std::stod(read_model(model).metadata.at("max_error_abs"));
  const auto report = dir_ / "r.json";
  CmdResult r = quadrix_run("mesh " + q(model) + " -o " + q(dir_ / "m.ply") + " --report " + q(report));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_DOUBLE_EQ(read_json(report)["mesh"]["bound"].get<double>(), fit_e);
  r = quadrix_run("mesh " + q(model) + " -o " + q(dir_ / "m.ply") + " --max-error 0.005 --allow-exceed --report " + q(report));
  ASSERT_EQ(r.code, 0) << r.out;
  // Of the model's own diagonal (its balls reach past the points).
  EXPECT_DOUBLE_EQ(read_json(report)["mesh"]["bound"].get<double>(), 0.005 * bounds(read_model(model)).diagonal());
}
