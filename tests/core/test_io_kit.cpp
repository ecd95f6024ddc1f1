// The I/O kit: hardening corpus for the core readers, format dispatch, STL and PLY meshes,
// normals from faces, bounded reads (the checked-in corpus: tests/convert/test_malformed_corpus.cpp).
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <zlib.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>

#include "core/error.h"
#include "core/io/file.h"
#include "core/io/io.h"
#include "core/model_io.h"
#include "tests/core/malformed_corpus.h"

namespace quadrix {
namespace {

using test::ScratchDir;
using test::write_bytes;

void read_with(const std::string& reader, const std::filesystem::path& p) {
  if (reader == "model") read_model(p);
  else if (reader == "mesh") read_mesh(p);
  else read_points(p);
}

TEST(IoKit, HardeningCorpusRefusedWithFileNameAndBoundedMessages) {
  ScratchDir dir("io-kit");
  const auto cases = test::make_io_corpus(dir.path());
  ASSERT_GE(cases.size(), 18u);
  for (const auto& c : cases) {
    SCOPED_TRACE(c.path.filename().string());
    try {
      read_with(c.reader, c.path);
      ADD_FAILURE() << "accepted";
    } catch (const FormatError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find(c.path.filename().string()), std::string::npos) << m;
      EXPECT_NE(m.find(c.expected), std::string::npos) << "expected '" << c.expected << "' in: " << m;
      EXPECT_LT(m.size(), 600u) << "message too long";
      for (unsigned char ch : m) EXPECT_TRUE(ch >= 0x20 || ch == '\n') << "control byte in: " << m;
    }
  }
}

TEST(IoKit, FolderIsIoErrorNamingIt) {
  ScratchDir dir("io-kit");
  for (const char* name : {"d.qxm", "d.slim2t", "d.xyz", "d.off", "d.ply", "d.stl"}) {
    std::filesystem::create_directories(dir / name);
    for (const std::string reader : {"model", "mesh", "points"}) {
      const bool is_model = std::string(name) == "d.qxm" || std::string(name) == "d.slim2t";
      if ((reader == "model") != is_model) continue;
      try {
        read_with(reader, dir / name);
        ADD_FAILURE() << name << " accepted";
      } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("folder"), std::string::npos) << e.what();
      }
    }
  }
}

TEST(IoKit, DevZeroIsBounded) {
  if (!std::filesystem::exists("/dev/zero")) GTEST_SKIP() << "no /dev/zero";
  EXPECT_THROW(io::read_file("/dev/zero", 1 << 20), FormatError);
}

// A prefix holds what the file has, up to the bound, and takes memory for that only: a header
// sniffed with a 1 MiB bound must not cost 1 MiB, and an unbounded prefix is the whole file.
TEST(IoKit, FilePrefixTakesWhatTheFileHoldsNotTheBound) {
  ScratchDir dir("io-kit");
  const std::string text = "NRRD0004\ntype: float\n" + std::string(200000, 'x');
  write_bytes(dir / "h.nhdr", text);
  const std::string small = io::read_file_prefix(dir / "h.nhdr", 1 << 20);
  EXPECT_EQ(small, text);
  EXPECT_LT(small.capacity(), std::size_t{1} << 19) << "the prefix holds memory for the bound, not the file";
  EXPECT_EQ(io::read_file_prefix(dir / "h.nhdr", io::kNoLimit), text);
  EXPECT_EQ(io::read_file_prefix(dir / "h.nhdr", 9), "NRRD0004\n");
  EXPECT_EQ(io::read_file_prefix(dir / "h.nhdr", 0), "");
  EXPECT_EQ(io::read_file_prefix(dir / "h.nhdr", 70000), text.substr(0, 70000));  // across the 64 KiB chunks
  if (std::filesystem::exists("/dev/zero")) {
    EXPECT_EQ(io::read_file_prefix("/dev/zero", 100000), std::string(100000, '\0'));
  }
}

TEST(IoKit, GzipBombStopsAtTheBound) {
  ScratchDir dir("io-kit");
  const auto p = dir / "bomb.gz";
  gzFile f = gzopen(p.string().c_str(), "wb9");
  const std::string zeros(1 << 20, '\0');
  for (int i = 0; i < 64; ++i) gzwrite(f, zeros.data(), static_cast<unsigned>(zeros.size()));
  gzclose(f);
  EXPECT_LT(std::filesystem::file_size(p), 200000u);
  try {
    io::read_gzip(p, 1000);
    ADD_FAILURE() << "accepted";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("1000 bytes"), std::string::npos) << e.what();
  }
  EXPECT_EQ(io::read_gzip(p, 1000, true).size(), 1000u);
}

TEST(IoKit, EchoCutsAndEscapes) {
  EXPECT_EQ(io::echo("abc"), "abc");
  EXPECT_EQ(io::echo("a\x01"), "a\\x01");
  const std::string e = io::echo(std::string(1000, 'x'));
  EXPECT_EQ(e.substr(0, 80), std::string(80, 'x'));
  EXPECT_NE(e.find("1000 bytes"), std::string::npos);
  EXPECT_LT(e.size(), 100u);
}

// A unit cube as 12 triangles, outward winding.
PolygonMesh cube() {
  PolygonMesh m;
  for (int i = 0; i < 8; ++i) m.vertices.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  const int f[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : f) {
    m.add_face(std::vector<int>{q[0], q[1], q[2]});
    m.add_face(std::vector<int>{q[0], q[2], q[3]});
  }
  return m;
}

std::string stl_ascii(const PolygonMesh& m) {
  std::string s = "solid cube\n";
  for (std::size_t f = 0; f < m.face_count(); ++f) {
    s += "facet normal 0 0 0\n outer loop\n";
    for (int v : m.face(f))
      s += fmt::format("  vertex {} {} {}\n", m.vertices[v].x(), m.vertices[v].y(), m.vertices[v].z());
    s += " endloop\nendfacet\n";
  }
  return s + "endsolid cube\n";
}

std::string stl_binary(const PolygonMesh& m) {
  std::string s(80, ' ');
  const auto n = static_cast<std::uint32_t>(m.face_count());
  s.append(reinterpret_cast<const char*>(&n), 4);
  for (std::size_t f = 0; f < m.face_count(); ++f) {
    float v[12] = {};
    int k = 3;
    for (int i : m.face(f))
      for (int a = 0; a < 3; ++a) v[k++] = static_cast<float>(m.vertices[i][a]);
    s.append(reinterpret_cast<const char*>(v), 48);
    s.append(2, '\0');
  }
  return s;
}

std::string ply_mesh(const PolygonMesh& m, const std::string& enc) {
  test::PlyDoc d;
  test::PlyElem v{"vertex", {{"double", "x", ""}, {"double", "y", ""}, {"double", "z", ""}}, {}, {}};
  for (const auto& p : m.vertices) v.rows.push_back({p.x(), p.y(), p.z()});
  test::PlyElem f{"face", {{"int", "vertex_indices", "uchar"}}, {}, {}};
  for (std::size_t i = 0; i < m.face_count(); ++i) {
    std::vector<double> r = {double(m.face(i).size())};
    for (int k : m.face(i)) r.push_back(k);
    f.rows.push_back(r);
  }
  d.elements = {v, f};
  return test::encode_ply(d, enc);
}

TEST(IoKit, EveryMeshFormatReadsTheSameCube) {
  ScratchDir dir("io-kit");
  const PolygonMesh m = cube();
  write_mesh(m, dir / "c.off");
  write_mesh(m, dir / "c.obj");
  write_bytes(dir / "c.stl", stl_ascii(m));
  write_bytes(dir / "b.stl", stl_binary(m));
  write_bytes(dir / "solid_named.stl", stl_binary(m).replace(0, 5, "solid"));  // binary despite "solid"
  for (const char* enc : {"ascii", "binary_little_endian", "binary_big_endian"})
    write_bytes(dir / (std::string(enc) + ".ply"), ply_mesh(m, enc));
  write_bytes(dir / "noext", ply_mesh(m, "ascii"));
  for (const char* name : {"c.off", "c.obj", "c.stl", "b.stl", "solid_named.stl", "ascii.ply",
                           "binary_little_endian.ply", "binary_big_endian.ply", "noext"}) {
    SCOPED_TRACE(name);
    EXPECT_EQ(detect_file_kind(dir / name), FileKind::mesh);
    const PolygonMesh r = read_mesh(dir / name);
    EXPECT_EQ(r.vertices.size(), 8u);
    EXPECT_EQ(r.face_count(), 12u);
    const PointCloud c = read_surface_points(dir / name);
    ASSERT_EQ(c.points.size(), 8u);
    for (std::size_t i = 0; i < 8; ++i)  // outward: along the corner's direction from the centre
      EXPECT_GT(c.normals[i].dot(c.points[i] - Eigen::Vector3d(0.5, 0.5, 0.5)), 0.5);
  }
}

TEST(IoKit, ClosedMeshNormalsPointOutwardWhateverTheWinding) {
  PolygonMesh m = cube();
  for (std::size_t f = 0; f < m.face_count(); ++f)
    std::reverse(m.indices.begin() + m.offsets[f], m.indices.begin() + m.offsets[f + 1]);
  const PointCloud c = points_from_mesh(m);
  ASSERT_EQ(c.points.size(), 8u);
  for (std::size_t i = 0; i < 8; ++i)
    EXPECT_GT(c.normals[i].dot(c.points[i] - Eigen::Vector3d(0.5, 0.5, 0.5)), 0.5);
  // Area weighting: a corner's normal is the (normalised) sum of its faces' area vectors.
  EXPECT_NEAR(c.normals[0].norm(), 1.0, 1e-15);
}

// A UV sphere with every other face wound the wrong way (a mesh assembled from parts exported
// apart): its vertices' face normals cancelled, and a fit of it drew a hole at every turned face
// (a quarter of its silhouette) and exited 0. The reader turns them to agree with their
// neighbours: a closed part ends outward, an open one keeps the larger area's winding; turned
// faces keep their first vertex (so a twisted quad its fan); a Möbius strip is left alone.
TEST(IoKit, FacesWoundAgainstTheirNeighboursAreTurned) {
  PolygonMesh m;
  const int rings = 10, segments = 16;
  m.vertices.emplace_back(0, 0, 1);
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double th = M_PI * i / rings, ph = 2 * M_PI * j / segments;
      // Rings slightly twisted: the quads are not planar.
      m.vertices.emplace_back(std::sin(th) * std::cos(ph + 0.05 * i), std::sin(th) * std::sin(ph + 0.05 * i), std::cos(th));
    }
  m.vertices.emplace_back(0, 0, -1);
  const int south = int(m.vertices.size()) - 1;
  const auto at = [&](int i, int j) { return 1 + (i - 1) * segments + (j % segments); };
  for (int j = 0; j < segments; ++j) m.add_face(std::array<int, 3>{0, at(1, j), at(1, j + 1)});
  for (int i = 1; i + 1 < rings; ++i)
    for (int j = 0; j < segments; ++j) m.add_face(std::array<int, 4>{at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
  for (int j = 0; j < segments; ++j) m.add_face(std::array<int, 3>{south, at(rings - 1, j + 1), at(rings - 1, j)});
  // Turned keeping their first vertex, as the reader turns them.
  const auto turn = [](PolygonMesh& mesh, std::size_t f) {
    std::reverse(mesh.indices.begin() + mesh.offsets[f] + 1, mesh.indices.begin() + mesh.offsets[f + 1]);
  };
  const auto turn_all = [&](PolygonMesh mesh) {
    for (std::size_t f = 0; f < mesh.face_count(); ++f) turn(mesh, f);
    return mesh;
  };
  if (mesh_wound_inward(m)) m = turn_all(m);
  const PolygonMesh good = m;  // wound outward
  ASSERT_FALSE(mesh_wound_inward(good));
  ASSERT_EQ(orient_faces_coherently(m), 0u);
  EXPECT_EQ(m.indices, good.indices);
  // A closed mesh wound inward throughout is left as it is (its readers turn its normals).
  PolygonMesh inward = turn_all(good);
  EXPECT_EQ(orient_faces_coherently(inward), 0u);
  // Most of the area wound the wrong way: a closed mesh still ends wound outward.
  std::size_t wrong = 0;
  for (std::size_t f = 0; f < m.face_count(); f += 2, ++wrong) turn(m, f);
  for (std::size_t f = 1; f < m.face_count(); f += 4, ++wrong) turn(m, f);
  EXPECT_EQ(orient_faces_coherently(m), wrong);
  EXPECT_EQ(m.indices, good.indices);
  // Normals from the faces: outward at every vertex, none cancelled.
  const PointCloud c = points_from_mesh(m);
  ASSERT_EQ(c.points.size(), m.vertices.size());
  for (std::size_t i = 0; i < c.points.size(); ++i) EXPECT_GT(c.normals[i].dot(c.points[i]), 0.9) << i;
  // Open (the south cap left out): the winding of the larger area wins.
  PolygonMesh open;
  open.vertices = good.vertices;
  for (std::size_t f = 0; f + segments < good.face_count(); ++f) open.add_face(good.face(f));
  const PolygonMesh open_good = open;
  std::size_t open_wrong = 0;
  for (std::size_t f = 0; f < open.face_count(); f += 2, ++open_wrong) turn(open, f);
  for (std::size_t f = 1; f < open.face_count(); f += 4, ++open_wrong) turn(open, f);
  EXPECT_EQ(orient_faces_coherently(open), open.face_count() - open_wrong);  // the kept ones were the fewer
  EXPECT_EQ(open.indices, turn_all(open_good).indices);  // every face the good one reversed: the same fans
  // Through the reader, with the file's name in the warning's place.
  ScratchDir dir("io-kit");
  PolygonMesh mixed = good;
  for (std::size_t f = 0; f < mixed.face_count(); f += 3) turn(mixed, f);
  write_mesh(mixed, dir / "mixed.obj");
  const PolygonMesh r = read_mesh(dir / "mixed.obj");
  EXPECT_EQ(r.indices, good.indices);
  // A Möbius strip cannot be wound one way: left as it is, nothing turned.
  PolygonMesh strip;
  const int n = 12;
  for (int k = 0; k < n; ++k) {
    const double t = 2 * M_PI * k / n;
    for (const double w : {-0.2, 0.2})
      strip.vertices.emplace_back((1 + w * std::cos(t / 2)) * std::cos(t), (1 + w * std::cos(t / 2)) * std::sin(t), w * std::sin(t / 2));
  }
  for (int k = 0; k < n; ++k) {
    const int a = 2 * k, b = 2 * k + 1, c2 = k + 1 < n ? 2 * k + 2 : 1, d = k + 1 < n ? 2 * k + 3 : 0;  // the twist
    strip.add_face(std::array<int, 4>{a, c2, d, b});
  }
  const PolygonMesh strip_before = strip;
  EXPECT_EQ(orient_faces_coherently(strip), 0u);
  EXPECT_EQ(strip.indices, strip_before.indices);
  turn(strip, 5);  // one face more against its neighbours: still nothing to gain
  EXPECT_EQ(orient_faces_coherently(strip), 0u);
}

// A strip of small triangles beside one triangle 10x larger: only the large one gets a lattice,
// every sample lies on its face with the face's normal, and no point of the large face is farther
// than about the small faces' size from a sample or a corner.
TEST(IoKit, FaceSamplesCoverLargeFaces) {
  PolygonMesh m;
  for (int i = 0; i <= 20; ++i) m.vertices.push_back({0.1 * i, 0, 0}), m.vertices.push_back({0.1 * i, 0.1, 0});
  for (int i = 0; i < 20; ++i) {
    const int a = 2 * i, b = a + 1, c = a + 2, d = a + 3;
    m.add_face(std::vector<int>{a, c, d});
    m.add_face(std::vector<int>{a, d, b});
  }
  const int p = int(m.vertices.size());
  m.vertices.push_back({0, 0.1, 0}), m.vertices.push_back({1, 0.1, 0}), m.vertices.push_back({0, 1.1, 0});
  m.add_face(std::vector<int>{p, p + 1, p + 2});
  const PointCloud centroids = face_centroids(m), samples = face_samples(m);
  ASSERT_EQ(centroids.points.size(), 41u);
  ASSERT_GT(samples.points.size(), centroids.points.size() + 40);
  for (std::size_t i = centroids.points.size(); i < samples.points.size(); ++i) {
    const Eigen::Vector3d& q = samples.points[i];
    EXPECT_NEAR(q.z(), 0.0, 1e-15);
    EXPECT_GE(q.y(), 0.1 - 1e-12);
    EXPECT_LE(q.x() + q.y(), 1.1 + 1e-12);
    EXPECT_NEAR(std::abs(samples.normals[i].z()), 1.0, 1e-12);
  }
  // Every point of the large face is within 0.1 (the lattice spacing, about the small faces'
  // longest edge 0.141) of a sample or one of its corners; with centroids only, 0.33 away.
  double worst = 0, worst_centroids = 0;
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; i + j <= 40; ++j) {
      const Eigen::Vector3d x(i / 40.0, 0.1 + j / 40.0, 0);
      double d = std::min({(x - m.vertices[p]).norm(), (x - m.vertices[p + 1]).norm(), (x - m.vertices[p + 2]).norm()});
      double dc = d;
      for (const auto& q : centroids.points) dc = std::min(dc, (x - q).norm());
      for (const auto& q : samples.points) d = std::min(d, (x - q).norm());
      worst = std::max(worst, d), worst_centroids = std::max(worst_centroids, dc);
    }
  EXPECT_LE(worst, 0.1);
  EXPECT_GT(worst_centroids, 0.3);
}

TEST(IoKit, PlyKindsByContent) {
  ScratchDir dir("io-kit");
  write_model(test::make_sample_model(false), dir / "m.ply");
  EXPECT_EQ(detect_file_kind(dir / "m.ply"), FileKind::model);
  EXPECT_EQ(read_model(dir / "m.ply").slims.size(), 3u);
  test::PlyDoc d;
  d.elements.push_back({"vertex", {{"float", "x", ""}, {"float", "y", ""}, {"float", "z", ""}}, {{0, 0, 0}}, {}});
  write_bytes(dir / "p.ply", test::encode_ply(d, "ascii"));
  EXPECT_EQ(detect_file_kind(dir / "p.ply"), FileKind::points);
  EXPECT_EQ(read_points(dir / "p.ply").points.size(), 1u);
  // Named for no format: known by content (a PLY header), else unknown (read as XYZ).
  std::filesystem::copy_file(dir / "p.ply", dir / "p.scan");
  EXPECT_EQ(known_file_kind(dir / "p.scan"), FileKind::points);
  write_bytes(dir / "notes.md", "0 0 0\n");
  EXPECT_EQ(known_file_kind(dir / "notes.md"), std::nullopt);
  EXPECT_EQ(detect_file_kind(dir / "notes.md"), FileKind::points);
  EXPECT_EQ(known_file_kind(dir / "m.ply"), FileKind::model);
}

// A nearly closed mesh's winding is judged by its signed volume about its own centre: about the
// world origin, a box with a small hole in its top (0.07 % of its edges open) moved 1e5 up read
// as wound inward (the hole's cone to the origin outweighs the box), and fits measured against it
// were judged inside out.
TEST(IoKit, ANearlyClosedMeshFarFromTheOriginKeepsItsWinding) {
  constexpr int n = 30;
  PolygonMesh box;
  std::map<std::array<int, 3>, int> index;  // grid corners, shared between faces
  // Six faces of the unit cube, each an n × n grid of quads wound outward; the top (+y) lacks a
  // 2 × 2 block of cells.
  for (int axis = 0; axis < 3; ++axis)
    for (const int side : {0, 1}) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      const auto at = [&](int i, int j) {
        std::array<int, 3> key{};
        key[axis] = side * n, key[u] = i, key[w] = j;
        const auto [it, added] = index.try_emplace(key, int(box.vertices.size()));
        if (added) box.vertices.emplace_back(double(key[0]) / n, double(key[1]) / n, double(key[2]) / n);
        return it->second;
      };
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          if (axis == 1 && side == 1 && i >= 10 && i < 12 && j >= 10 && j < 12) continue;
          const int a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
          // (u, w, axis) is right-handed: counter-clockwise seen from +axis is a, b, c, d.
          if (side == 1) box.add_face(std::array<int, 4>{a, b, c, d});
          else box.add_face(std::array<int, 4>{a, d, c, b});
        }
    }
  ASSERT_EQ(orient_faces_coherently(box), 0u);
  ASSERT_FALSE(mesh_wound_inward(box));
  for (auto& v : box.vertices) v.y() += 1e5;
  EXPECT_FALSE(mesh_wound_inward(box));
}

}  // namespace
}  // namespace quadrix
