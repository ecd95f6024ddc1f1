// Polygon mesh (OFF/OBJ/PLY), PNG and PFM I/O: real data sets, round trips, malformed files.
#include <gtest/gtest.h>

#include "tests/support.h"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <random>
#include <string>

#include <unistd.h>

#include "core/error.h"
#include "core/image.h"
#include "core/mesh_io.h"

namespace fs = std::filesystem;
using namespace quadrix;

namespace {

fs::path dataset(const std::string& relative) { return fs::path(QUADRIX_DATASETS) / relative; }

#define REQUIRE_DATASET(p)                                                                   \
  do {                                                                                       \
    if (!fs::exists(p)) GTEST_SKIP() << "data set not found: " << (p).string()              \
                                     << " (QUADRIX_DATASETS=" QUADRIX_DATASETS ")";          \
  } while (0)

std::map<std::size_t, std::size_t> face_size_histogram(const PolygonMesh& mesh) {
  std::map<std::size_t, std::size_t> h;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) ++h[mesh.face(f).size()];
  return h;
}

void expect_valid(const PolygonMesh& mesh) {
  ASSERT_EQ(mesh.offsets.front(), 0);
  ASSERT_EQ(static_cast<std::size_t>(mesh.offsets.back()), mesh.indices.size());
  for (const int v : mesh.indices) {
    ASSERT_GE(v, 0);
    ASSERT_LT(static_cast<std::size_t>(v), mesh.vertices.size());
  }
  for (const auto& p : mesh.vertices) ASSERT_TRUE(p.allFinite());
}

using test_support::TempDir;

/// Expects a FormatError whose message names the file (and, if given, contains `also`).
template <typename F>
void expect_format_error(F&& f, const fs::path& file, const std::string& also = {}) {
  try {
    f();
    ADD_FAILURE() << "no FormatError for " << file;
  } catch (const FormatError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(file.filename().string()), std::string::npos) << msg;
    if (!also.empty()) {
      EXPECT_NE(msg.find(also), std::string::npos) << msg;
    }
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Real data

TEST(MeshIoData, CubeQuadOff) {
  const auto p = dataset("quads/cube_quad.off");
  REQUIRE_DATASET(p);
  const PolygonMesh m = read_mesh(p);
  expect_valid(m);
  EXPECT_EQ(m.vertices.size(), 8u);
  EXPECT_EQ(m.face_count(), 6u);
  EXPECT_EQ(face_size_histogram(m), (std::map<std::size_t, std::size_t>{{4, 6}}));
  // First face of the file: "4  0 3 7 4", vertex 7 = (1, -1, 1).
  const auto f0 = m.face(0);
  EXPECT_EQ(std::vector<int>(f0.begin(), f0.end()), (std::vector<int>{0, 3, 7, 4}));
  EXPECT_EQ(m.vertices[7], Eigen::Vector3d(1, -1, 1));
}

TEST(MeshIoData, BeastObjFaceSizes) {
  const auto p = dataset("quads/beast.obj");
  REQUIRE_DATASET(p);
  const PolygonMesh m = read_mesh(p);
  expect_valid(m);
  EXPECT_EQ(m.vertices.size(), 32311u);
  EXPECT_EQ(m.face_count(), 32364u);
  EXPECT_EQ(face_size_histogram(m), (std::map<std::size_t, std::size_t>{{3, 124}, {4, 32228}, {5, 10}, {6, 2}}));
  // "f 1/1 2/2 3/3 4/4": texture indices are dropped, OBJ's 1-based indices become 0-based.
  const auto f0 = m.face(0);
  EXPECT_EQ(std::vector<int>(f0.begin(), f0.end()), (std::vector<int>{0, 1, 2, 3}));
}

TEST(MeshIoData, SuzanneObj) {
  const auto p = dataset("quads/suzanne.obj");
  REQUIRE_DATASET(p);
  const PolygonMesh m = read_mesh(p);
  expect_valid(m);
  EXPECT_EQ(m.vertices.size(), 507u);
  EXPECT_EQ(face_size_histogram(m), (std::map<std::size_t, std::size_t>{{3, 32}, {4, 468}}));
}

TEST(MeshIoData, BunnyPly) {
  const auto p = dataset("meshes/bunny.ply");
  REQUIRE_DATASET(p);
  const PolygonMesh m = read_mesh(p);
  expect_valid(m);
  EXPECT_EQ(m.vertices.size(), 35947u);
  EXPECT_EQ(m.face_count(), 69451u);
  EXPECT_EQ(face_size_histogram(m), (std::map<std::size_t, std::size_t>{{3, 69451}}));
  // First vertex line: "-0.0378297 0.12794 0.00447467 0.850855 0.5" (float32 in the file).
  EXPECT_FLOAT_EQ(static_cast<float>(m.vertices[0].x()), -0.0378297f);
  EXPECT_FLOAT_EQ(static_cast<float>(m.vertices[0].y()), 0.12794f);
  EXPECT_FLOAT_EQ(static_cast<float>(m.vertices[0].z()), 0.00447467f);
}

TEST(MeshIoData, FandiskOff) {
  const auto p = dataset("meshes/fandisk.off");
  REQUIRE_DATASET(p);
  const PolygonMesh m = read_mesh(p);
  expect_valid(m);
  EXPECT_EQ(m.vertices.size(), 6475u);
  EXPECT_EQ(m.face_count(), 12946u);
  EXPECT_EQ(face_size_histogram(m), (std::map<std::size_t, std::size_t>{{3, 12946}}));
}

// ---------------------------------------------------------------------------------------------
// Round trips

namespace {
PolygonMesh mixed_mesh() {
  // A pyramid with a quad base plus a pentagon fan to mix face sizes; awkward coordinates
  // to check lossless printing (up to 1e12, the largest world coordinate: core/limits.h).
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1e3, 1e3);
  PolygonMesh m;
  for (int i = 0; i < 9; ++i) m.vertices.emplace_back(u(rng), u(rng) * 1e-9, u(rng) * 1e9);
  m.vertices.emplace_back(0.1, 1.0 / 3.0, -0.0);
  m.add_face(std::vector<int>{0, 1, 2, 3});
  m.add_face(std::vector<int>{0, 4, 1});
  m.add_face(std::vector<int>{1, 4, 2});
  m.add_face(std::vector<int>{2, 4, 3});
  m.add_face(std::vector<int>{3, 4, 0});
  m.add_face(std::vector<int>{5, 6, 7, 8, 9});
  return m;
}
}  // namespace

class MeshIoRoundTrip : public TempDir, public ::testing::WithParamInterface<const char*> {};

TEST_P(MeshIoRoundTrip, ExactVerticesAndFaces) {
  const PolygonMesh m = mixed_mesh();
  const fs::path p = dir_ / (std::string("mesh") + GetParam());
  write_mesh(m, p);
  const PolygonMesh r = read_mesh(p);
  ASSERT_EQ(r.vertices.size(), m.vertices.size());
  for (std::size_t v = 0; v < m.vertices.size(); ++v) EXPECT_EQ(r.vertices[v], m.vertices[v]) << "vertex " << v;
  EXPECT_EQ(r.indices, m.indices);
  EXPECT_EQ(r.offsets, m.offsets);
  // No temporary file left beside the target.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

INSTANTIATE_TEST_SUITE_P(Formats, MeshIoRoundTrip, ::testing::Values(".obj", ".off", ".OBJ", ".ply"));

TEST_F(MeshIoRoundTrip, PlyColoursAndStlTrianglesReadBack) {
  PolygonMesh m = mixed_mesh();
  for (std::size_t v = 0; v < m.vertices.size(); ++v)
    m.colours.push_back({static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(255 - v), 7});
  write_mesh(m, dir_ / "c.ply");
  EXPECT_EQ(read_mesh(dir_ / "c.ply").colours, m.colours);
  // STL: polygons fanned into triangles, float32 coordinates.
  write_mesh(m, dir_ / "c.stl");
  const PolygonMesh s = read_mesh(dir_ / "c.stl");
  std::size_t triangles = 0;
  for (std::size_t f = 0; f < m.face_count(); ++f) triangles += m.face(f).size() - 2;
  EXPECT_EQ(s.face_count(), triangles);
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    const auto v = s.face(f);
    ASSERT_EQ(v.size(), 3u);
    for (const int i : v) {
      double nearest = 1e300;
      for (const auto& p : m.vertices) nearest = std::min(nearest, (p - s.vertices[i]).norm());
      EXPECT_LT(nearest, 1e-6 * (1 + s.vertices[i].norm()));
    }
  }
}

TEST_P(MeshIoRoundTrip, NormalsAndColoursReadBack) {
  // Per-vertex normals (float32 in every format) beside colours: PLY nx/ny/nz, OFF's CNOFF
  // columns (the normal before the colour), OBJ's vn with faces v//vn.
  PolygonMesh m = mixed_mesh();
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    m.normals.push_back(Eigen::Vector3d(std::cos(0.7 * v), std::sin(0.7 * v), 0.3 * v - 1.0).normalized());
    m.colours.push_back({static_cast<std::uint8_t>(10 * v), 20, static_cast<std::uint8_t>(255 - v)});
  }
  const fs::path p = dir_ / (std::string("n") + GetParam());
  write_mesh(m, p);
  const PolygonMesh r = read_mesh(p);
  ASSERT_EQ(r.normals.size(), m.normals.size()) << p;
  for (std::size_t v = 0; v < m.normals.size(); ++v) EXPECT_LT((r.normals[v] - m.normals[v]).norm(), 1e-6) << "vertex " << v;
  for (std::size_t v = 0; v < m.vertices.size(); ++v) EXPECT_EQ(r.vertices[v], m.vertices[v]) << "vertex " << v;
  EXPECT_EQ(r.indices, m.indices);
  // Colours come back from PLY, OFF (CNOFF, 0-255) and OBJ (v x y z r g b, 0-1 to 4 digits): the
  // OFF and OBJ readers skipped them, so a mesh Quadrix wrote in colour read back grey.
  EXPECT_EQ(r.colours, m.colours) << p;
  // Colours without normals (COFF, OBJ's v x y z r g b alone) come back too.
  {
    PolygonMesh c = m;
    c.normals.clear();
    write_mesh(c, p);
    EXPECT_EQ(read_mesh(p).colours, m.colours) << p;
  }
  // Without normals, none come back.
  m.normals.clear();
  write_mesh(m, p);
  EXPECT_TRUE(read_mesh(p).normals.empty());
  // A normal per vertex or none.
  m.normals.assign(m.vertices.size() - 1, Eigen::Vector3d::UnitZ());
  EXPECT_THROW(write_mesh(m, dir_ / (std::string("bad") + GetParam())), InvalidInput);
  m.normals.assign(m.vertices.size(), Eigen::Vector3d::Zero());
  EXPECT_THROW(write_mesh(m, dir_ / (std::string("bad") + GetParam())), InvalidInput);
}

class MeshIo : public TempDir {};

TEST_F(MeshIo, WriteRejectsBadInput) {
  PolygonMesh m = mixed_mesh();
  EXPECT_THROW(write_mesh(m, dir_ / "m.xyz"), InvalidInput);
  m.vertices[2].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(write_mesh(m, dir_ / "m.obj"), InvalidInput);
  EXPECT_FALSE(fs::exists(dir_ / "m.obj"));
}

TEST_F(MeshIo, ObjNegativeIndicesAndExtras) {
  const auto p = write_text("neg.obj",
                            "# comment\nmtllib x.mtl\no thing\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                            "vt 0 0\nvn 0 0 1\ns off\nf -4/1/1 -3/1/1 -2/1/1 -1/1/1\nv 0 0 1\nf 1//1 -1//1 2//1\n");
  const PolygonMesh m = read_mesh(p);
  EXPECT_EQ(m.vertices.size(), 5u);
  ASSERT_EQ(m.face_count(), 2u);
  EXPECT_EQ(std::vector<int>(m.face(0).begin(), m.face(0).end()), (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(std::vector<int>(m.face(1).begin(), m.face(1).end()), (std::vector<int>{0, 4, 1}));
}

TEST_F(MeshIo, NonManifoldFacesAreKept) {
  // Three triangles sharing edge 0-1: OpenMesh's halfedge mesh refuses the third; we keep it.
  const auto p = write_text("fin.off", "OFF\n5 3 0\n0 0 0\n1 0 0\n0 1 0\n0 -1 0\n0 0 1\n3 0 1 2\n3 1 0 3\n3 0 1 4\n");
  ::testing::internal::CaptureStderr();
  const PolygonMesh m = read_mesh(p);
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(m.vertices.size(), 5u);
  EXPECT_EQ(m.face_count(), 3u);
  EXPECT_NE(log.find("1 of 3 faces"), std::string::npos) << log;
  EXPECT_NE(log.find("fin.off"), std::string::npos) << log;
}

TEST_F(MeshIo, BinaryPlyKeepsQuads) {
  // binary_little_endian PLY with an extra vertex property and one quad + one triangle.
  std::string s =
      "ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
      "property float z\nproperty float confidence\nelement face 2\nproperty list uchar int vertex_indices\n"
      "end_header\n";
  const float xyz[5][4] = {{0, 0, 0, 1}, {1, 0, 0, 1}, {1, 1, 0, 1}, {0, 1, 0, 1}, {0.5f, 0.25f, -1e-3f, 1}};
  for (const auto& v : xyz) s.append(reinterpret_cast<const char*>(v), sizeof v);
  auto face = [&](std::initializer_list<int> idx) {
    s.push_back(static_cast<char>(idx.size()));
    for (const int i : idx) s.append(reinterpret_cast<const char*>(&i), 4);
  };
  face({0, 1, 2, 3});
  face({1, 0, 4});
  const auto p = write_text("bin.ply", s);
  const PolygonMesh m = read_mesh(p);
  ASSERT_EQ(m.vertices.size(), 5u);
  EXPECT_EQ(m.vertices[4], Eigen::Vector3d(0.5, 0.25, static_cast<double>(-1e-3f)));
  EXPECT_EQ(face_size_histogram(m), (std::map<std::size_t, std::size_t>{{3, 1}, {4, 1}}));
  EXPECT_EQ(std::vector<int>(m.face(1).begin(), m.face(1).end()), (std::vector<int>{1, 0, 4}));
  // Declared 2 faces, only one present.
  const auto t = write_text("bin_trunc.ply", s.substr(0, s.size() - 13));
  expect_format_error([&] { read_mesh(t); }, t);
}

// ---------------------------------------------------------------------------------------------
// Malformed meshes

TEST_F(MeshIo, MissingFileIsIoError) { EXPECT_THROW(read_mesh(dir_ / "nope.off"), IoError); }

TEST_F(MeshIo, TruncatedOff) {
  const auto p = write_text("trunc.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n");
  expect_format_error([&] { read_mesh(p); }, p, "truncated");
  const auto q = write_text("trunc_v.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n");
  expect_format_error([&] { read_mesh(q); }, q, "truncated");
  const auto r = write_text("short_face.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n");
  expect_format_error([&] { read_mesh(r); }, r);
}

TEST_F(MeshIo, NanVertex) {
  const auto p = write_text("nan.off", "OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n");
  expect_format_error([&] { read_mesh(p); }, p, "vertex 1");
  const auto q = write_text("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 inf\nf 1 2 3\n");
  expect_format_error([&] { read_mesh(q); }, q, "vertex 3");
  const auto r = write_text("word.obj", "v 0 0 zero\nf 1 1 1\n");
  expect_format_error([&] { read_mesh(r); }, r, "vertex 0");
}

TEST_F(MeshIo, OutOfRangeIndex) {
  const auto p = write_text("range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  expect_format_error([&] { read_mesh(p); }, p, "out of range");
  const auto q = write_text("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
  expect_format_error([&] { read_mesh(q); }, q, "out of range");
  const auto r = write_text("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
  expect_format_error([&] { read_mesh(r); }, r, "index 0");
  const auto s = write_text("neg.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n");
  expect_format_error([&] { read_mesh(s); }, s, "out of range");
}

TEST_F(MeshIo, OutOfRangeIndexPly) {
  const auto p = write_text("range.ply",
                            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                            "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                            "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
  expect_format_error([&] { read_mesh(p); }, p, "out of range");
}

TEST_F(MeshIo, EmptyAndFacelessFiles) {
  for (const char* name : {"empty.off", "empty.obj", "empty.ply"}) {
    const auto p = write_text(name, "");
    expect_format_error([&] { read_mesh(p); }, p);
  }
  const auto c = write_text("comments.obj", "# nothing here\n\n");
  expect_format_error([&] { read_mesh(c); }, c);
  const auto v = write_text("points.obj", "v 0 0 0\nv 1 0 0\n");
  expect_format_error([&] { read_mesh(v); }, v, "no faces");
  const auto o = write_text("points.off", "OFF\n1 0 0\n0 0 0\n");
  expect_format_error([&] { read_mesh(o); }, o, "no faces");
  const auto g = write_text("garbage.off", "solid stl\nfacet normal 0 0 1\n");
  expect_format_error([&] { read_mesh(g); }, g, "not an OFF");
}

// ---------------------------------------------------------------------------------------------
// Images

class ImageIo : public TempDir {};

TEST_F(ImageIo, PngRoundTrip) {
  Image8 img;
  img.width = 37;  // odd sizes catch row-stride mistakes
  img.height = 11;
  img.rgba.resize(37 * 11 * 4);
  std::mt19937 rng(3);
  for (auto& b : img.rgba) b = static_cast<std::uint8_t>(rng());
  const fs::path p = dir_ / "img.png";
  write_png(img, p);
  const Image8 r = read_png(p);
  EXPECT_EQ(r.width, 37);
  EXPECT_EQ(r.height, 11);
  EXPECT_EQ(r.rgba, img.rgba);
}

TEST_F(ImageIo, PngCorruptAndMissing) {
  EXPECT_THROW(read_png(dir_ / "missing.png"), IoError);
  const auto p = write_text("text.png", "this is not a png");
  expect_format_error([&] { read_png(p); }, p);
  // A valid PNG cut in half.
  Image8 img;
  img.width = img.height = 64;
  img.rgba.resize(64 * 64 * 4);
  std::mt19937 rng(5);
  for (auto& b : img.rgba) b = static_cast<std::uint8_t>(rng());
  const fs::path full = dir_ / "full.png";
  write_png(img, full);
  std::ifstream in(full, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto half = write_text("half.png", bytes.substr(0, bytes.size() / 2));
  expect_format_error([&] { read_png(half); }, half);
}

class PfmRoundTrip : public TempDir, public ::testing::WithParamInterface<int> {};

TEST_P(PfmRoundTrip, ExactAndTopRowFirst) {
  FloatImage img;
  img.width = 5;
  img.height = 3;
  img.channels = GetParam();
  img.data.resize(5 * 3 * img.channels);
  for (std::size_t i = 0; i < img.data.size(); ++i) img.data[i] = static_cast<float>(i) * 0.25f - 1.0f;
  img.data[1] = std::numeric_limits<float>::infinity();  // background depth
  const fs::path p = dir_ / "img.pfm";
  write_pfm(img, p);

  // On disk: header, then the bottom image row first, little-endian.
  std::ifstream in(p, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string header = std::string(img.channels == 3 ? "PF" : "Pf") + "\n5 3\n-1\n";
  ASSERT_EQ(bytes.substr(0, header.size()), header);
  ASSERT_EQ(bytes.size(), header.size() + img.data.size() * 4);
  float first_on_disk;
  std::memcpy(&first_on_disk, bytes.data() + header.size(), 4);
  EXPECT_EQ(first_on_disk, img.data[2 * 5 * img.channels]);  // row 2 = bottom row

  const FloatImage r = read_pfm(p);
  EXPECT_EQ(r.width, 5);
  EXPECT_EQ(r.height, 3);
  EXPECT_EQ(r.channels, img.channels);
  EXPECT_EQ(r.data, img.data);
}

INSTANTIATE_TEST_SUITE_P(Channels, PfmRoundTrip, ::testing::Values(1, 3));

TEST_F(ImageIo, PfmBigEndianRead) {
  // Scale +1 means big-endian data; one 2×1 gray image = {1.0, -2.0}.
  std::string s = "Pf\n2 1\n1.0\n";
  s += std::string("\x3f\x80\x00\x00\xc0\x00\x00\x00", 8);
  const auto p = write_text("be.pfm", s);
  const FloatImage r = read_pfm(p);
  ASSERT_EQ(r.data.size(), 2u);
  EXPECT_EQ(r.data[0], 1.0f);
  EXPECT_EQ(r.data[1], -2.0f);
}

TEST_F(ImageIo, PfmMalformed) {
  EXPECT_THROW(read_pfm(dir_ / "missing.pfm"), IoError);
  const auto magic = write_text("magic.pfm", "P6\n2 2\n255\n");
  expect_format_error([&] { read_pfm(magic); }, magic, "not a PFM");
  const auto dims = write_text("dims.pfm", "Pf\n0 2\n-1\n");
  expect_format_error([&] { read_pfm(dims); }, dims, "width");
  const auto huge = write_text("huge.pfm", "PF\n70000 2\n-1\n");
  expect_format_error([&] { read_pfm(huge); }, huge, "width");
  const auto scale = write_text("scale.pfm", "Pf\n1 1\nabc\n");
  expect_format_error([&] { read_pfm(scale); }, scale, "scale");
  const auto zero = write_text("zero.pfm", "Pf\n1 1\n0\n");
  expect_format_error([&] { read_pfm(zero); }, zero, "scale");
  const auto header_only = write_text("header.pfm", "Pf\n2");
  expect_format_error([&] { read_pfm(header_only); }, header_only);
  const auto trunc = write_text("trunc.pfm", std::string("PF\n2 2\n-1\n") + std::string(40, '\0'));
  expect_format_error([&] { read_pfm(trunc); }, trunc, "truncated");
  const auto empty = write_text("empty.pfm", "");
  expect_format_error([&] { read_pfm(empty); }, empty);
}

TEST_F(ImageIo, WriteRejectsBadImages) {
  FloatImage f;
  f.width = 2;
  f.height = 2;
  f.channels = 2;
  f.data.resize(8);
  EXPECT_THROW(write_pfm(f, dir_ / "x.pfm"), InvalidInput);
  Image8 i;
  i.width = 2;
  i.height = 2;
  i.rgba.resize(3);
  EXPECT_THROW(write_png(i, dir_ / "x.png"), InvalidInput);
  EXPECT_FALSE(fs::exists(dir_ / "x.png"));
}

// OFF and OBJ vertex colours as writers write them: 0-255, or 0-1 (every value of the file at
// most 1, as %g prints pure red "1 0 0"; a vertex written with a point and at most 1 beside
// 0-255 ones, Geomview's rule); OBJ's v x y z w is a weight. A damaged colour column costs the
// colours, not the geometry (the readers ignored the columns before and read such files).
TEST(MeshIoColours, OffAndObjColoursReadAsWritersWriteThem) {
  const fs::path dir = fs::temp_directory_path() / ("quadrix_colours_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const auto read = [&](const char* name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return read_mesh(dir / name);
  };
  using Colours = std::vector<std::array<std::uint8_t, 3>>;
  const std::string off = "COFF\n3 1 0\n", face = "3 0 1 2\n";
  EXPECT_EQ(read("i.off", off + "0 0 0 255 0 0 255\n1 0 0 0 128 0 255\n0 1 0 0 0 7 255\n" + face).colours,
            (Colours{{255, 0, 0}, {0, 128, 0}, {0, 0, 7}}));
  EXPECT_EQ(read("f.off", off + "0 0 0 1.0 0 0 1\n1 0 0 0 0.5 0 1\n0 1 0 0 0 1 1\n" + face).colours,
            (Colours{{255, 0, 0}, {0, 128, 0}, {0, 0, 255}}));
  EXPECT_EQ(read("g.off", off + "0 0 0 1 0 0 1\n1 0 0 0 1 0 1\n0 1 0 0 0 1 1\n" + face).colours,
            (Colours{{255, 0, 0}, {0, 255, 0}, {0, 0, 255}}));
  EXPECT_EQ(read("m.off", off + "0 0 0 200 100 50 255\n1 0 0 0.5 0.5 0.5 1\n0 1 0 0 0 7 255\n" + face).colours,
            (Colours{{200, 100, 50}, {128, 128, 128}, {0, 0, 7}}));
  EXPECT_EQ(read("c.obj", "v 0 0 0 1 0 0\nv 1 0 0 0 0.5 0\nv 0 1 0 0 0 1\nf 1 2 3\n").colours,
            (Colours{{255, 0, 0}, {0, 128, 0}, {0, 0, 255}}));
  EXPECT_EQ(read("b.obj", "v 0 0 0 255 0 0\nv 1 0 0 0 128 0\nv 0 1 0 0 0 7\nf 1 2 3\n").colours,
            (Colours{{255, 0, 0}, {0, 128, 0}, {0, 0, 7}}));
  EXPECT_TRUE(read("w.obj", "v 0 0 0 1\nv 1 0 0 1\nv 0 1 0 1\nf 1 2 3\n").colours.empty());
  EXPECT_TRUE(read("some.obj", "v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 0 0 1\nf 1 2 3\n").colours.empty());  // one per vertex or none
  // Damaged columns: the geometry is read, the colours left out.
  for (const auto& [name, text] : std::vector<std::pair<const char*, std::string>>{
           {"nan.obj", "v 0 0 0 nan 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n"},
           {"abc.obj", "v 0 0 0 abc 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n"},
           {"big.obj", "v 0 0 0 300 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n"},
           {"neg.off", off + "0 0 0 -1 0 0 255\n1 0 0 0 128 0 255\n0 1 0 0 0 7 255\n" + face}}) {
    const PolygonMesh m = read(name, text);
    EXPECT_EQ(m.vertices.size(), 3u) << name;
    EXPECT_EQ(m.face_count(), 1u) << name;
    EXPECT_TRUE(m.colours.empty()) << name;
  }
  fs::remove_all(dir);
}
