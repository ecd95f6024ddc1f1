#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "core/error.h"
#include "core/points_io.h"
#include "tests/core/malformed_corpus.h"

namespace quadrix {
namespace {

using test::ScratchDir;
using test::write_bytes;

const std::filesystem::path kDatasets = QUADRIX_DATASETS;

#define REQUIRE_DATASET(rel)                            \
  const std::filesystem::path path = kDatasets / (rel); \
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "dataset missing: " << path.string()

void expect_unit_normals(const PointCloud& c) {
  ASSERT_EQ(c.normals.size(), c.points.size());
  for (const auto& n : c.normals) ASSERT_NEAR(n.norm(), 1.0, 1e-12);
}

/// Message check: the error names the file and contains what.
void expect_format_error(const std::filesystem::path& p, const std::string& what) {
  try {
    const PointCloud c = read_points(p);
    ADD_FAILURE() << p.filename() << ": no exception, " << c.points.size() << " points";
  } catch (const FormatError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(p.filename().string()), std::string::npos) << m;
    EXPECT_NE(m.find(what), std::string::npos) << "expected '" << what << "' in: " << m;
  }
}

TEST(PointsDatasets, KittenXyzWithNormals) {
  REQUIRE_DATASET("points/kitten.xyz");
  const PointCloud c = read_points(path);
  EXPECT_EQ(c.points.size(), 5210u);
  expect_unit_normals(c);
  EXPECT_NEAR(c.points[0].x(), -0.0721898, 1e-12);
}

TEST(PointsDatasets, RadarXyzWithoutNormals) {
  REQUIRE_DATASET("points/radar.xyz");
  const PointCloud c = read_points(path);
  EXPECT_EQ(c.points.size(), 20950u);
  EXPECT_FALSE(c.has_normals());
  EXPECT_NEAR(c.points[0].x(), -99.7385919424, 1e-9);
}

TEST(PointsDatasets, RawScanPlySkipsRangeGrid) {
  REQUIRE_DATASET("points/bun000_rawscan.ply");
  const PointCloud c = read_points(path);
  EXPECT_EQ(c.points.size(), 40256u);
  EXPECT_FALSE(c.has_normals());
}

TEST(PointsDatasets, BunnyMeshPlyVertices) {
  REQUIRE_DATASET("meshes/bunny.ply");
  const PointCloud c = read_points(path);
  EXPECT_EQ(c.points.size(), 35947u);
  EXPECT_NEAR(c.points[0].x(), -0.0378297, 1e-7);
  EXPECT_NEAR(c.points[2].z(), 0.0371953, 1e-7);
}

TEST(PointsDatasets, CubeQuadOffVertices) {
  REQUIRE_DATASET("quads/cube_quad.off");
  const PointCloud c = read_points(path);
  ASSERT_EQ(c.points.size(), 8u);
  for (const auto& p : c.points) EXPECT_EQ(p.cwiseAbs(), Eigen::Vector3d::Ones());
}

TEST(PointsDatasets, DragonObjVertices) {
  REQUIRE_DATASET("meshes/dragon_10k.obj");
  const PointCloud c = read_points(path);
  EXPECT_EQ(c.points.size(), 10000u);
  EXPECT_NEAR(c.points[0].x(), 0.247004, 1e-12);
}

TEST(PointsXyz, CommentsBlankLinesAndNormalisation) {
  ScratchDir dir("points-io");
  write_bytes(dir / "a.xyz", "# header\n\n1 2 3 0 0 2\n  4 5 6 3 0 4  \r\n# more\n7 8 9e-1 0 -1 0\n");
  const PointCloud c = read_points(dir / "a.xyz");
  ASSERT_EQ(c.points.size(), 3u);
  EXPECT_EQ(c.points[2], Eigen::Vector3d(7, 8, 0.9));
  EXPECT_EQ(c.normals[0], Eigen::Vector3d(0, 0, 1));
  EXPECT_NEAR((c.normals[1] - Eigen::Vector3d(0.6, 0, 0.8)).norm(), 0, 1e-15);
  expect_unit_normals(c);
}

TEST(PointsXyz, MalformedFiles) {
  ScratchDir dir("points-io");
  write_bytes(dir / "mixed.xyz", "1 2 3\n4 5 6\n1 2 3 0 0 1\n");
  expect_format_error(dir / "mixed.xyz", ":3:");
  write_bytes(dir / "cols.txt", "1 2 3\n1 2 3 4\n");
  expect_format_error(dir / "cols.txt", "4 values");
  write_bytes(dir / "nan.xyz", "1 2 3\n\n1 nan 3\n");
  expect_format_error(dir / "nan.xyz", ":3:");
  write_bytes(dir / "token.pts", "1 2 3\n1 two 3\n");
  expect_format_error(dir / "token.pts", ":2:3: 'two' is not a number");
  // A zero normal among given ones (and the other way round) is refused where they first mix.
  write_bytes(dir / "zero.xyz", "1 2 3 0 0 1\n4 5 6 0 1 0\n7 8 9 0 0 0\n");
  expect_format_error(dir / "zero.xyz", ":3:");
  expect_format_error(dir / "zero.xyz", "zero normal (line 1 has a non-zero one");
  write_bytes(dir / "zero_first.xyz", "1 2 3 0 0 0\n4 5 6 0 0 1\n");
  expect_format_error(dir / "zero_first.xyz", ":2:");
  expect_format_error(dir / "zero_first.xyz", "after line 1's zero normal");
  write_bytes(dir / "empty.xyz", "# nothing\n\n");
  expect_format_error(dir / "empty.xyz", "no points");
  write_bytes(dir / "count.pts", "3\n1 2 3\n4 5 6\n");
  expect_format_error(dir / "count.pts", "declares 3 points");
  // Line numbers count CR LF (and a doubled CR CR LF) and a lone CR (classic Mac OS) as one line end each.
  write_bytes(dir / "crlf.xyz", "1 2 3\r\n4 5 6\r\r\n1 two 3\r\n");
  expect_format_error(dir / "crlf.xyz", ":3:3: 'two' is not a number");
  write_bytes(dir / "cr.xyz", "1 2 3\r4 5 6\r1 two 3\r");
  expect_format_error(dir / "cr.xyz", ":3:3: 'two' is not a number");
}

// Exporters write "0 0 0" for "no normal" (CGAL's demo cloud blobby.xyz, 3,288 rows of them,
// was refused: "blobby.xyz:1:67: zero normal"): all zero reads as a cloud without normals.
TEST(PointsXyz, AllZeroNormalsMeanNone) {
  ScratchDir dir("points-io");
  write_bytes(dir / "none.xyz", "1 2 3 0 0 0\n4 5 6 0 0 0\n7 8 9 0 0 0\n");
  const PointCloud c = read_points(dir / "none.xyz");
  ASSERT_EQ(c.points.size(), 3u);
  EXPECT_FALSE(c.has_normals());
  EXPECT_EQ(c.points[2], Eigen::Vector3d(7, 8, 9));
  write_bytes(dir / "none9.xyz", "1 2 3 0 0 0 10 20 30\n4 5 6 0 0 0 40 50 60\n");
  const PointCloud d = read_points(dir / "none9.xyz");
  EXPECT_FALSE(d.has_normals());
  ASSERT_EQ(d.colours.size(), 2u);
  EXPECT_EQ(d.colours[1][2], 60);
}

// Windows editors start a UTF-8 file with a byte order mark; classic Mac OS ends lines with CR.
// Both were refused ("'\xef\xbb\xbf0.0199' is not a number"; 30,000 values on line 1).
TEST(PointsXyz, ByteOrderMarkAndCarriageReturnLines) {
  ScratchDir dir("points-io");
  write_bytes(dir / "bom.xyz", "\xEF\xBB\xBF" "1 2 3 0 0 1\n4 5 6 0 1 0\n");
  write_bytes(dir / "cr.xyz", "1 2 3 0 0 1\r4 5 6 0 1 0\r");
  write_bytes(dir / "bom_cr.xyz", "\xEF\xBB\xBF" "1 2 3 0 0 1\r\n4 5 6 0 1 0");
  for (const char* name : {"bom.xyz", "cr.xyz", "bom_cr.xyz"}) {
    SCOPED_TRACE(name);
    const PointCloud c = read_points(dir / name);
    ASSERT_EQ(c.points.size(), 2u);
    EXPECT_EQ(c.points[0], Eigen::Vector3d(1, 2, 3));
    EXPECT_EQ(c.normals[1], Eigen::Vector3d(0, 1, 0));
  }
}

TEST(PointsXyz, WriteReadRoundTripIsExact) {
  ScratchDir dir("points-io");
  PointCloud c;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g;
  for (int i = 0; i < 100; ++i) {
    c.points.emplace_back(g(rng), g(rng) * 1e-7, g(rng) * 1e9);
    c.normals.push_back(Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized());
  }
  write_points_xyz(c, dir / "out.xyz");
  const PointCloud r = read_points(dir / "out.xyz");
  EXPECT_EQ(r.points, c.points);
  ASSERT_EQ(r.normals.size(), c.normals.size());
  for (std::size_t i = 0; i < c.normals.size(); ++i) EXPECT_NEAR((r.normals[i] - c.normals[i]).norm(), 0, 1e-15);
  c.normals.clear();
  write_points_xyz(c, dir / "plain.xyz");
  const PointCloud p = read_points(dir / "plain.xyz");
  EXPECT_EQ(p.points, c.points);
  EXPECT_FALSE(p.has_normals());
}

// Coloured scans: XYZ's nine-column form (x y z nx ny nz r g b) and PLY's red/green/blue reach
// PointCloud::colours, one per point; the XYZ writer writes them back.
TEST(PointsColours, XyzNineColumnsAndPlyRgb) {
  ScratchDir dir("points-io");
  write_bytes(dir / "c.xyz", "1 2 3 0 0 1 255 0 7\n4 5 6 0 1 0 10 20 30\n");
  PointCloud c = read_points(dir / "c.xyz");
  ASSERT_EQ(c.colours.size(), 2u);
  EXPECT_EQ(c.colours[0], (std::array<std::uint8_t, 3>{255, 0, 7}));
  EXPECT_EQ(c.colours[1], (std::array<std::uint8_t, 3>{10, 20, 30}));
  write_points_xyz(c, dir / "out.xyz");
  EXPECT_EQ(read_points(dir / "out.xyz").colours, c.colours);
  write_bytes(dir / "bad.xyz", "1 2 3 0 0 1 255 0 7\n4 5 6 0 1 0 10 256 30\n");
  expect_format_error(dir / "bad.xyz", ":2:");
  write_bytes(dir / "frac.xyz", "1 2 3 0 0 1 0.5 0 7\n");
  expect_format_error(dir / "frac.xyz", "colour value 0.5");
  write_bytes(dir / "c.ply",
              "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
              "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n0 0 0 1 2 3\n1 0 0 4 5 6\n");
  c = read_points(dir / "c.ply");
  ASSERT_EQ(c.colours.size(), 2u);
  EXPECT_EQ(c.colours[1], (std::array<std::uint8_t, 3>{4, 5, 6}));
  write_bytes(dir / "plain.xyz", "1 2 3\n");
  EXPECT_FALSE(read_points(dir / "plain.xyz").has_colours());
}

test::PlyDoc vertex_doc(bool normals) {
  test::PlyDoc d;
  test::PlyElem v{
      "vertex", {{"float", "x", ""}, {"float", "y", ""}, {"float", "z", ""}, {"uchar", "flags", ""}}, {}, {}};
  if (normals) v.props.insert(v.props.end(), {{"double", "nx", ""}, {"double", "ny", ""}, {"double", "nz", ""}});
  for (int i = 0; i < 5; ++i) {
    std::vector<double> r = {0.5 * i, -1.0 * i, 2.0, 7};
    if (normals) r.insert(r.end(), {0.0, 3.0, 4.0});
    v.rows.push_back(r);
  }
  d.elements.push_back(v);
  d.elements.push_back({"face", {{"int", "vertex_indices", "uchar"}}, {{3, 0, 1, 2}, {4, 0, 1, 2, 3}}, {}});
  return d;
}

TEST(PointsPly, AllEncodingsWithAndWithoutNormals) {
  ScratchDir dir("points-io");
  for (bool normals : {false, true}) {
    for (const char* enc : {"ascii", "binary_little_endian", "binary_big_endian"}) {
      SCOPED_TRACE(std::string(enc) + (normals ? " normals" : ""));
      const auto path = dir / (std::string(enc) + ".ply");
      write_bytes(path, test::encode_ply(vertex_doc(normals), enc));
      const PointCloud c = read_points(path);
      ASSERT_EQ(c.points.size(), 5u);
      EXPECT_EQ(c.points[3], Eigen::Vector3d(1.5, -3, 2));
      EXPECT_EQ(c.has_normals(), normals);
      if (normals) {
        EXPECT_NEAR((c.normals[4] - Eigen::Vector3d(0, 0.6, 0.8)).norm(), 0, 1e-15);
      }
    }
  }
}

TEST(PointsPly, AllZeroNormalsMeanNoneAndMixedAreRefused) {
  ScratchDir dir("points-io");
  test::PlyDoc d = vertex_doc(true);
  for (std::size_t i = 0; i < 5; ++i)
    for (const char* p : {"nx", "ny", "nz"}) d.set("vertex", i, p, 0.0);
  write_bytes(dir / "none.ply", test::encode_ply(d, "binary_little_endian"));
  const PointCloud c = read_points(dir / "none.ply");
  EXPECT_EQ(c.points.size(), 5u);
  EXPECT_FALSE(c.has_normals());
  d.set("vertex", 3, "nz", 1.0);
  write_bytes(dir / "mixed.ply", test::encode_ply(d, "ascii"));
  expect_format_error(dir / "mixed.ply", "element 'vertex' row 3 property 'nx'");
  expect_format_error(dir / "mixed.ply", "after vertex 0's zero normal");
  d = vertex_doc(true);
  d.set("vertex", 2, "nx", 0.0), d.set("vertex", 2, "ny", 0.0), d.set("vertex", 2, "nz", 0.0);
  write_bytes(dir / "mixed2.ply", test::encode_ply(d, "binary_big_endian"));
  expect_format_error(dir / "mixed2.ply", "element 'vertex' row 2 property 'nx'");
  expect_format_error(dir / "mixed2.ply", "zero normal (vertex 0's is not");
}

TEST(PointsPly, MalformedFiles) {
  ScratchDir dir("points-io");
  {
    test::PlyDoc d = vertex_doc(true);
    d.remove_property("vertex", "nz");
    write_bytes(dir / "partial.ply", test::encode_ply(d, "binary_little_endian"));
    expect_format_error(dir / "partial.ply", "nx ny nz");
  }
  {
    test::PlyDoc d = vertex_doc(false);
    d.set("vertex", 3, "y", std::numeric_limits<double>::infinity());
    write_bytes(dir / "inf.ply", test::encode_ply(d, "binary_big_endian"));
    expect_format_error(dir / "inf.ply", "element 'vertex' row 3 property 'y'");
  }
  {
    test::PlyDoc d = vertex_doc(false);
    d.elements[0].count_override = "1000000000000000000";
    write_bytes(dir / "absurd.ply", test::encode_ply(d, "ascii"));
    expect_format_error(dir / "absurd.ply", "element 'vertex'");
  }
  {
    test::PlyDoc d = vertex_doc(false);
    d.elements[1].rows[1][0] = 200;  // list count beyond the file
    write_bytes(dir / "list.ply", test::encode_ply(d, "binary_little_endian"));
    expect_format_error(dir / "list.ply", "element 'face' row 1 property 'vertex_indices'");
    write_bytes(dir / "list_ascii.ply", test::encode_ply(d, "ascii"));
    expect_format_error(dir / "list_ascii.ply", "element 'face' row 1 property 'vertex_indices'");
  }
  {
    test::PlyDoc d = vertex_doc(false);
    d.elements[0].name = "points";
    write_bytes(dir / "novertex.ply", test::encode_ply(d, "ascii"));
    expect_format_error(dir / "novertex.ply", "vertex");
  }
  {
    test::PlyDoc d = vertex_doc(false);
    d.elements[0].rows.clear();
    d.elements[1].rows.clear();
    write_bytes(dir / "none.ply", test::encode_ply(d, "binary_little_endian"));
    expect_format_error(dir / "none.ply", "no points");
  }
}

TEST(PointsOffObj, VariantsAndValidation) {
  ScratchDir dir("points-io");
  write_bytes(dir / "n.off", "NOFF\n# c\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 2\n0 1 0 0 3 0\n3 0 1 2\n");
  PointCloud c = read_points(dir / "n.off");
  ASSERT_EQ(c.points.size(), 3u);
  EXPECT_EQ(c.normals[2], Eigen::Vector3d(0, 1, 0));
  write_bytes(dir / "c.off", "COFF 2 0 0\n0 0 0 255 0 0 255\n1 2 3 0 255 0 255\n");
  c = read_points(dir / "c.off");
  ASSERT_EQ(c.points.size(), 2u);
  EXPECT_EQ(c.points[1], Eigen::Vector3d(1, 2, 3));
  EXPECT_FALSE(c.has_normals());
  write_bytes(dir / "big.off", "OFF\n1000000000000 0 0\n0 0 0\n");
  expect_format_error(dir / "big.off", ":2:");
  write_bytes(dir / "short.off", "OFF\n3 0 0\n0 0 0\n1 1 1\n");
  expect_format_error(dir / "short.off", "truncated");
  write_bytes(dir / "faces.off", "OFF\n3 5 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  expect_format_error(dir / "faces.off", "5 faces");
  write_bytes(dir / "nan.off", "OFF\n2 0 0\n0 0 0\n1 inf 0\n");
  expect_format_error(dir / "nan.off", ":4:");

  write_bytes(dir / "a.obj", "# obj\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 2\nvn 0 0 1\nvn 0 0 1\nf 1 2 3\n");
  c = read_points(dir / "a.obj");
  ASSERT_EQ(c.points.size(), 3u);
  ASSERT_TRUE(c.has_normals());
  EXPECT_EQ(c.normals[0], Eigen::Vector3d(0, 0, 1));
  write_bytes(dir / "b.obj", "v 0 0 0\nv 1 0 0\nvn 0 0 1\nvt 0 0\nf 1 2 1\n");
  c = read_points(dir / "b.obj");
  EXPECT_EQ(c.points.size(), 2u);
  EXPECT_FALSE(c.has_normals());  // normal count differs from the vertex count
  write_bytes(dir / "bad.obj", "v 0 0 0\nv 1 x 0\n");
  expect_format_error(dir / "bad.obj", ":2:");
  write_bytes(dir / "none.obj", "# nothing\nf 1 2 3\n");
  expect_format_error(dir / "none.obj", "no points");
}

TEST(PointsIo, MissingFileIsIoError) {
  ScratchDir dir("points-io");
  EXPECT_THROW(read_points(dir / "missing.xyz"), IoError);
  EXPECT_THROW(read_points(dir / "missing.ply"), IoError);
}

}  // namespace
}  // namespace quadrix
