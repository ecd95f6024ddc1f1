#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <sstream>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <random>

#include <fmt/format.h>

#include "core/bvh.h"
#include "core/camera.h"
#include "core/error.h"
#include "core/mesh_io.h"
#include "core/model_io.h"
#include "core/reference.h"
#include "core/io/ply.h"
#include "tests/core/malformed_corpus.h"

namespace quadrix {
namespace {

using test::encode_ply;
using test::make_sample_model;
using test::qxm_doc;
using test::ScratchDir;
using test::write_bytes;

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

template <class M>
bool same_bits(const M& a, const M& b) {
  for (Eigen::Index i = 0; i < a.size(); ++i)
    if (!same_bits(a.data()[i], b.data()[i])) return false;
  return true;
}

bool same_bits(const Quadric& a, const Quadric& b) {
  return same_bits(a.A, b.A) && same_bits(a.b, b.b) && same_bits(a.c, b.c);
}

/// Bit-exact comparison of the primitives (metadata compared by the callers).
void expect_same_primitives(const Model& a, const Model& b) {
  ASSERT_EQ(a.slims.size(), b.slims.size());
  ASSERT_EQ(a.tets.size(), b.tets.size());
  ASSERT_EQ(a.glyphs.size(), b.glyphs.size());
  for (std::size_t i = 0; i < a.slims.size(); ++i) {
    const SlimPatch &x = a.slims[i], &y = b.slims[i];
    EXPECT_TRUE(same_bits(x.centre, y.centre)) << "slim " << i;
    EXPECT_TRUE(same_bits(x.radius, y.radius)) << "slim " << i;
    EXPECT_TRUE(same_bits(x.local, y.local)) << "slim " << i;
    ASSERT_EQ(x.clips.size(), y.clips.size()) << "slim " << i;
    for (int k = 0; k < x.clips.size(); ++k)
      EXPECT_TRUE(same_bits(x.clips[k].n, y.clips[k].n) && same_bits(x.clips[k].d, y.clips[k].d)) << "slim " << i;
    EXPECT_EQ(x.colour, y.colour) << "slim " << i;
  }
  for (std::size_t i = 0; i < a.tets.size(); ++i) {
    for (int k = 0; k < 4; ++k) EXPECT_TRUE(same_bits(a.tets[i].corners[k], b.tets[i].corners[k])) << "tet " << i;
    EXPECT_TRUE(same_bits(a.tets[i].quadric, b.tets[i].quadric)) << "tet " << i;
    EXPECT_EQ(a.tets[i].colour, b.tets[i].colour) << "tet " << i;
  }
  for (std::size_t i = 0; i < a.glyphs.size(); ++i) {
    const Glyph &x = a.glyphs[i], &y = b.glyphs[i];
    EXPECT_EQ(x.kind, y.kind) << "glyph " << i;
    EXPECT_TRUE(same_bits(x.centre, y.centre) && same_bits(x.radius, y.radius) && same_bits(x.axes, y.axes))
        << "glyph " << i;
    EXPECT_EQ(x.colour, y.colour) << "glyph " << i;
  }
}

std::map<std::string, std::string> without_bbox(std::map<std::string, std::string> m) {
  m.erase("bbox");
  return m;
}

TEST(ModelIo, RoundTripIsBitExactWithOptionalProperties) {
  ScratchDir dir("model-io");
  const Model m = make_sample_model(true);
  // Mixed clip planes: none, one, several (revision 4's clip2_* to clip4_*).
  ASSERT_TRUE(m.slims[1].clips.empty() && m.slims[0].clips.size() == 1 && m.slims[2].clips.size() == 3);
  write_model(m, dir / "m.qxm", {.encoding = ModelEncoding::full});
  const Model r = read_model(dir / "m.qxm");
  expect_same_primitives(m, r);
  EXPECT_EQ(without_bbox(r.metadata), m.metadata);
}

TEST(ModelIo, RoundTripIsBitExactWithoutOptionalProperties) {
  ScratchDir dir("model-io");
  const Model m = make_sample_model(false);
  write_model(m, dir / "m.qxm", {.encoding = ModelEncoding::full});
  const std::string bytes = test::read_bytes(dir / "m.qxm");
  const std::string header = bytes.substr(0, bytes.find("end_header"));
  EXPECT_EQ(header.find("clip_nx"), std::string::npos);
  EXPECT_EQ(header.find("red"), std::string::npos);
  expect_same_primitives(m, read_model(dir / "m.qxm"));
}

TEST(ModelIo, HeaderFollowsTheProfile) {
  ScratchDir dir("model-io");
  Model m = make_sample_model(true);
  m.metadata["bad key"] = "skipped";
  m.metadata["note"] = "two\nlines";
  m.tets.clear();
  write_model(m, dir / "m.qxm");
  const std::string bytes = test::read_bytes(dir / "m.qxm");
  EXPECT_EQ(bytes.rfind("ply\nformat binary_little_endian 1.0\ncomment quadrix-format 4\ncomment quadrix-encoding "
                        "compact\ncomment quadrix-origin ",
                        0),
            0u);
  const ply::File f = ply::File::open(dir / "m.qxm");
  ASSERT_NE(f.header().find("slim"), nullptr);
  EXPECT_EQ(f.header().find("tet"), nullptr);  // empty elements are left out
  const ply::Element& g = *f.header().find("glyph");
  EXPECT_EQ(g.properties[0].name, "kind");
  EXPECT_EQ(g.properties[0].type, ply::Type::uint8);
  EXPECT_EQ(g.properties.back().name, "blue");
  EXPECT_EQ(g.properties.back().type, ply::Type::uint8);
  const Model r = read_model(dir / "m.qxm");
  EXPECT_EQ(r.metadata.count("bad key"), 0u);
  EXPECT_EQ(r.metadata.at("note"), "two lines");
  EXPECT_EQ(r.metadata.count("quadrix-format"), 0u);
  // bbox metadata equals the model's bounds.
  std::istringstream bb(r.metadata.at("bbox"));
  Eigen::Vector3d lo, hi;
  bb >> lo.x() >> lo.y() >> lo.z() >> hi.x() >> hi.y() >> hi.z();
  const Box3 box = bounds(m);
  EXPECT_TRUE(lo.isApprox(box.min, 1e-12) && hi.isApprox(box.max, 1e-12));
}

TEST(ModelIo, EmptyModelWritesEveryElementWithCountZero) {
  ScratchDir dir("model-io");
  write_model(Model{}, dir / "empty.qxm");
  const ply::File f = ply::File::open(dir / "empty.qxm");
  for (const char* e : {"slim", "tet", "glyph"}) {
    ASSERT_NE(f.header().find(e), nullptr) << e;
    EXPECT_EQ(f.header().find(e)->count, 0u);
  }
  EXPECT_TRUE(read_model(dir / "empty.qxm").empty());
}

TEST(ModelIo, AsciiAndBigEndianEncodingsReadBackEqual) {
  ScratchDir dir("model-io");
  for (bool optional : {false, true}) {
    const Model m = make_sample_model(optional);
    for (const char* enc : {"ascii", "binary_big_endian", "binary_little_endian"}) {
      const auto path = dir / (std::string(enc) + ".qxm");
      write_bytes(path, encode_ply(qxm_doc(m), enc));
      SCOPED_TRACE(enc);
      const Model r = read_model(path);
      expect_same_primitives(m, r);
      EXPECT_EQ(r.metadata, m.metadata);
    }
  }
}

TEST(ModelIo, FloatColumnsAndExtraPropertiesAreAccepted) {
  ScratchDir dir("model-io");
  const Model m = make_sample_model(true);
  test::PlyDoc d = qxm_doc(m, "float");
  d.element("slim").props.push_back({"float", "confidence", ""});
  d.element("slim").props.push_back({"uchar", "tags", "uchar"});
  for (auto& row : d.element("slim").rows) row.insert(row.end(), {0.5, 2, 1, 2});
  d.elements.push_back({"junk", {{"int", "a", ""}}, {{1}, {2}}, {}});
  d.comments.push_back("units mm");
  for (const char* enc : {"ascii", "binary_big_endian", "binary_little_endian"}) {
    const auto path = dir / (std::string(enc) + ".qxm");
    write_bytes(path, encode_ply(d, enc));
    SCOPED_TRACE(enc);
    const Model r = read_model(path);
    ASSERT_EQ(r.slims.size(), m.slims.size());
    ASSERT_EQ(r.glyphs.size(), m.glyphs.size());
    const auto f = [](double v) { return static_cast<double>(static_cast<float>(v)); };
    if (std::string(enc) != "ascii") {  // binary float columns hold exactly the float values
      EXPECT_EQ(r.slims[0].radius, f(m.slims[0].radius));
      EXPECT_EQ(r.tets[2].corners[3].z(), f(m.tets[2].corners[3].z()));
    }
    EXPECT_NEAR(r.slims[0].radius, m.slims[0].radius, 1e-6);
    EXPECT_NEAR(r.glyphs[1].axes(2, 2), m.glyphs[1].axes(2, 2), 1e-6);
    EXPECT_EQ(r.slims[2].colour, m.slims[2].colour);
  }
}

TEST(ModelIo, WriteRejectsNonFiniteModels) {
  ScratchDir dir("model-io");
  Model m = make_sample_model(false);
  m.tets[1].corners[2].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(write_model(m, dir / "nan.qxm"), InvalidInput);
  EXPECT_FALSE(std::filesystem::exists(dir / "nan.qxm"));
}

TEST(ModelIo, MissingFileIsIoError) {
  ScratchDir dir("model-io");
  EXPECT_THROW(read_model(dir / "missing.qxm"), IoError);
}

TEST(ModelIo, MessagesNameFileElementRowPropertyAndByte) {
  ScratchDir dir("model-io");
  const Model m = make_sample_model(false);
  test::PlyDoc d = qxm_doc(m);
  d.set("slim", 2, "radius", -0.5);
  write_bytes(dir / "bunny.qxm", encode_ply(d, "binary_little_endian"));
  try {
    read_model(dir / "bunny.qxm");
    FAIL() << "no exception";
  } catch (const FormatError& e) {
    // Row size: 14 doubles; radius is the 4th column of row 2.
    const std::string body_hint = "element 'slim' row 2 property 'radius' at byte ";
    const std::string what = e.what();
    EXPECT_NE(what.find("bunny.qxm: "), std::string::npos) << what;
    EXPECT_NE(what.find(body_hint), std::string::npos) << what;
    EXPECT_NE(what.find("value -0.5 must be > 0"), std::string::npos) << what;
    const std::string bytes = test::read_bytes(dir / "bunny.qxm");
    const std::size_t expected_byte = bytes.find("end_header\n") + 11 + 2 * 14 * 8 + 3 * 8;
    EXPECT_NE(what.find(body_hint + std::to_string(expected_byte) + ":"), std::string::npos) << what;
  }
}

TEST(ModelIo, MalformedCorpusThrowsFormatErrors) {
  ScratchDir dir("model-io-corpus");
  const auto cases = test::make_malformed_corpus(dir.path());
  EXPECT_GE(cases.size(), 24u);
  for (const auto& c : cases) {
    SCOPED_TRACE(c.path.filename().string());
    try {
      const Model m = read_model(c.path);
      ADD_FAILURE() << "no exception; read " << m.size() << " primitives";
    } catch (const FormatError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(c.path.filename().string()), std::string::npos) << what;
      EXPECT_NE(what.find(c.expected), std::string::npos) << "expected '" << c.expected << "' in: " << what;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "not a FormatError: " << e.what();
    }
  }
}

// ------------------------------------------------------------------ .slim2t

struct Ball {
  std::array<float, 3> centre;
  std::array<float, 10> k;
  float radius;
  float parent;  // 1-based, −1 for a root: a float in the file, like every per-ball value
};

std::string slim2t_bytes(std::int32_t degree, const std::vector<Ball>& balls, std::int32_t nuser,
                         std::int32_t declared = -1) {
  std::string out;
  auto put = [&](auto v) { out.append(reinterpret_cast<const char*>(&v), sizeof v); };
  put(degree);
  put(declared >= 0 ? declared : static_cast<std::int32_t>(balls.size()));
  put(nuser);
  for (const Ball& b : balls) {
    for (float v : b.centre) put(v);
    for (float v : b.k) put(v);
    put(b.radius);
    put(b.parent);
    for (int u = 0; u < nuser; ++u) put(static_cast<float>(u) + 0.5f);
  }
  return out;
}

std::vector<Ball> sample_balls() {
  // 1 is the root; 2 and 3 its children; 4 a child of 2. Leaves: 3 and 4.
  return {
      {{0, 0, 0}, {1, 1, 1, 0, 0, 0, 0, 0, 0, -4}, 3.0f, -1},
      {{1, 0, 0}, {1, 1, 1, 0, 0, 0, 0, 0, 0, -1}, 1.5f, 1},
      {{-1.25f, 0.5f, 0.25f}, {1, 2, 0.5f, 0.1f, -0.2f, 0.3f, 0.4f, -0.5f, 0.6f, -0.7f}, 0.75f, 1},
      {{1.5f, -0.5f, 2}, {0, 0, 0, 0, 0, 0, 1, 2, -1, 0.25f}, 0.5f, 2},
  };
}

TEST(Slim2t, KeepsLeavesAndConvertsCoefficients) {
  ScratchDir dir("slim2t");
  const auto balls = sample_balls();
  for (std::int32_t degree : {2, -2}) {
    write_bytes(dir / "s.slim2t", slim2t_bytes(degree, balls, 2));
    const Model m = read_model(dir / "s.slim2t");
    ASSERT_EQ(m.slims.size(), 2u);
    // An unoriented file (degree < 0) may come back flipped as a whole, never leaf by leaf.
    const double sign = degree < 0 && m.metadata.at("slim2t_orientation").find("every ball was flipped") !=
                                          std::string::npos
                            ? -1.0
                            : 1.0;
    const Ball* src[2] = {&balls[2], &balls[3]};
    for (int i = 0; i < 2; ++i) {
      const SlimPatch& s = m.slims[i];
      const Ball& b = *src[i];
      EXPECT_EQ(s.radius, static_cast<double>(b.radius));
      const Eigen::Vector3d c(b.centre[0], b.centre[1], b.centre[2]);
      EXPECT_EQ(s.centre, c);
      QuadricCoefficients k;
      for (int j = 0; j < 10; ++j) k[j] = b.k[j];
      const Quadric original = Quadric::from_coefficients(k) * sign;  // local to the centre, unscaled
      const Quadric world = s.world();
      std::mt19937_64 rng(7);
      std::uniform_real_distribution<double> u(-2, 2);
      for (int t = 0; t < 20; ++t) {
        const Eigen::Vector3d x(u(rng), u(rng), u(rng));
        EXPECT_NEAR(world.eval(x), original.eval(x - c), 1e-9 * (1 + std::abs(original.eval(x - c))));
        // The local quadric is in u = (x − c)/R.
        EXPECT_NEAR(s.local.eval((x - c) / s.radius), original.eval(x - c),
                    1e-9 * (1 + std::abs(original.eval(x - c))));
      }
    }
  }
}

TEST(Slim2t, DispatchesOnMagicWithoutTheExtension) {
  ScratchDir dir("slim2t");
  write_bytes(dir / "s.bin", slim2t_bytes(1, sample_balls(), 0));
  EXPECT_EQ(read_model(dir / "s.bin").slims.size(), 2u);
  EXPECT_EQ(read_slim2t(dir / "s.bin").slims.size(), 2u);
}

TEST(Slim2t, MalformedFilesThrowFormatErrors) {
  ScratchDir dir("slim2t");
  auto balls = sample_balls();
  auto expect_error = [&](const std::string& name, const std::string& bytes, const std::string& expected) {
    write_bytes(dir / name, bytes);
    try {
      read_model(dir / name);
      ADD_FAILURE() << name << ": no exception";
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  expect_error("short.slim2t", std::string(7, '\0'), "truncated");
  expect_error("degree.slim2t", slim2t_bytes(3, balls, 0), "degree 3");
  expect_error("count.slim2t", slim2t_bytes(2, balls, 0, 1000000000), "truncated");
  expect_error("negative.slim2t",
               slim2t_bytes(2, balls, 0, 0).substr(0, 4) + std::string("\xff\xff\xff\xff", 4) + std::string(4, '\0'),
               "negative");
  expect_error("user.slim2t", slim2t_bytes(2, {}, 5000), "user value count");
  expect_error("cut.slim2t", slim2t_bytes(2, balls, 1).substr(0, 12 + 16 * 4 * 3 + 10), "ball 3");
  auto bad = balls;
  bad[1].radius = -1;
  expect_error("radius.slim2t", slim2t_bytes(2, bad, 0), "ball 1");
  bad = balls;
  bad[2].parent = 9;
  expect_error("parent.slim2t", slim2t_bytes(2, bad, 0), "parent id 9");
  bad = balls;
  bad[3].k[4] = std::numeric_limits<float>::infinity();
  expect_error("inf.slim2t", slim2t_bytes(2, bad, 0), "not finite");
  // Parent ids are integer-valued floats in {−1} ∪ [1, #balls], not the ball itself, no cycles.
  bad = balls;
  bad[2].parent = 1.5f;
  expect_error("fraction.slim2t", slim2t_bytes(2, bad, 0), "ball 2 at byte 188: parent id 1.5 is not an integer");
  bad = balls;
  bad[2].parent = 0.0f;
  expect_error("zero.slim2t", slim2t_bytes(2, bad, 0), "ball 2 at byte 188: parent id 0");
  bad = balls;
  bad[1].parent = -2.0f;
  expect_error("minus2.slim2t", slim2t_bytes(2, bad, 0), "ball 1 at byte 128: parent id -2");
  bad = balls;
  bad[1].parent = std::nanf("");
  expect_error("nan_parent.slim2t", slim2t_bytes(2, bad, 0), "ball 1 at byte 128: parent id value nan is not finite");
  bad = balls;
  bad[3].parent = 4.0f;
  expect_error("self.slim2t", slim2t_bytes(2, bad, 0), "ball 3 at byte 248: parent id 4 is the ball itself");
  bad = balls;
  bad[0].parent = 4.0f;  // 1 → 4 → 2 → 1
  expect_error("cycle.slim2t", slim2t_bytes(2, bad, 0), "parent links form a cycle");
  // Bytes after the declared balls are refused, named by their offset.
  expect_error("trailing.slim2t", slim2t_bytes(2, balls, 0) + std::string(3, '\0'),
               "at byte 252: 3 bytes follow the 4 declared balls");
  expect_error("extra_ball.slim2t", slim2t_bytes(2, balls, 0, 3), "60 bytes follow the 3 declared balls");
  // Errors (the first user value) are ≥ 0.
  std::string neg = slim2t_bytes(2, balls, 1);
  const float minus = -1.0f;
  std::memcpy(neg.data() + 12 + 64 + 60, &minus, 4);
  expect_error("error.slim2t", neg, "ball 1 at byte 136: error (first user value) -1 is negative");
}

TEST(Slim2t, KeepsTheHierarchyWithErrors) {
  ScratchDir dir("slim2t");
  write_bytes(dir / "s.slim2t", slim2t_bytes(2, sample_balls(), 2));  // errors: 0.5 for every ball
  const Model m = read_model(dir / "s.slim2t");
  // Leaves (file balls 2, 3) are ids 0, 1; interior balls (file 0, 1) ids 2, 3.
  ASSERT_EQ(m.slims.size(), 2u);
  const SlimHierarchy& h = m.slim_hierarchy;
  ASSERT_EQ(h.others.size(), 2u);
  EXPECT_EQ(h.parent, (std::vector<std::int32_t>{2, 3, -1, 2}));
  EXPECT_EQ(h.error, (std::vector<double>(4, 0.5)));
  EXPECT_EQ(h.others[0].radius, 3.0);
  EXPECT_EQ(h.others[1].centre, Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(validate_slim_hierarchy(m), "");
  const SlimHierarchyStats st = slim_hierarchy_stats(m);
  EXPECT_EQ(st.levels, 3u);
  EXPECT_EQ(st.leaves, 2u);
  EXPECT_EQ(st.interior, 2u);
  EXPECT_EQ(st.roots, 1u);
  EXPECT_EQ(m.metadata.at("slim2t_degree"), "2");
  EXPECT_EQ(m.metadata.count("slim2t_orientation"), 0u);  // positive degree: oriented, untouched
}

/// A hand-made hierarchy: 4 leaves (ids 0–3), interior 4 = {0, 1}, 5 = {4, 2}, root 6 = {5, 3}.
Model sample_hierarchy() {
  Model m;
  for (int i = 0; i < 4; ++i) {
    SlimPatch& s = m.slims.emplace_back();
    s.centre = Eigen::Vector3d(i, 0.5 * i, -i);
    s.radius = 0.25 + i;
    s.local = Quadric::sphere(Eigen::Vector3d::Zero(), 0.5);
    s.colour = Rgb{static_cast<std::uint8_t>(i), 2, 3};
  }
  m.slims[1].clips = ClipPlanes::of(ClipPlane{Eigen::Vector3d(0, 0, 1), 0.25});
  auto& h = m.slim_hierarchy;
  for (int i = 0; i < 3; ++i) {
    SlimPatch& s = h.others.emplace_back();
    s.centre = Eigen::Vector3d(0.1 * i, 1, 2);
    s.radius = 4.0 + i;
    s.local = Quadric::plane(Eigen::Vector3d(1, 2, 3), -0.1 * i);
    s.colour = Rgb{9, 8, static_cast<std::uint8_t>(i)};
  }
  h.parent = {4, 4, 5, 6, 5, 6, -1};
  h.error = {0, 0, 0, 0, 0.3, 0.7, 1.0 / 3.0};
  return m;
}

TEST(SlimHierarchy, CutByError) {
  Model m = sample_hierarchy();
  EXPECT_EQ(select_slim_cut(m, -1), (std::vector<std::int32_t>{0, 1, 2, 3}));
  EXPECT_EQ(select_slim_cut(m, 0.0), (std::vector<std::int32_t>{0, 1, 2, 3}));
  EXPECT_EQ(select_slim_cut(m, 0.3), (std::vector<std::int32_t>{2, 3, 4}));
  // Errors not monotone at the root (1/3 < 0.7): the walk from the root takes the root.
  EXPECT_EQ(select_slim_cut(m, 0.5), (std::vector<std::int32_t>{6}));
  m.slim_hierarchy.error[6] = 2.0;
  EXPECT_EQ(select_slim_cut(m, 0.7), (std::vector<std::int32_t>{3, 5}));
  EXPECT_EQ(select_slim_cut(m, 2.0), (std::vector<std::int32_t>{6}));
  m.slim_hierarchy.parent[6] = 5;  // 5 → 6 → 5
  EXPECT_NE(validate_slim_hierarchy(m).find("cycle"), std::string::npos) << validate_slim_hierarchy(m);
  EXPECT_THROW(select_slim_cut(m, 0.5), InvalidInput);
  m.slim_hierarchy.parent[6] = 6;
  EXPECT_NE(validate_slim_hierarchy(m).find("ball 6: parent 6 is itself"), std::string::npos);
  m.slim_hierarchy.parent.clear();
  m.slim_hierarchy.error.clear();
  m.slim_hierarchy.others.clear();
  EXPECT_EQ(select_slim_cut(m, 0.5), (std::vector<std::int32_t>{0, 1, 2, 3}));  // no hierarchy: all drawn
}

// A ball's own blend push bound (fit --lod-levels writes it on the coarser levels): the optional
// max_push column round-trips on the balls that have one, the others read none; a bound ≤ 0 is
// refused on write.
TEST(ModelIo, PerBallPushBoundRoundTrips) {
  ScratchDir dir("qxm_push");
  Model m = sample_hierarchy();
  for (auto& b : m.slim_hierarchy.others) b.max_push = 0.25;
  m.slim_hierarchy.others[1].max_push.reset();
  for (const auto encoding : {ModelEncoding::full, ModelEncoding::compact}) {
    write_model(m, dir / "p.qxm", {.encoding = encoding});
    const Model r = read_model(dir / "p.qxm");
    for (std::size_t i = 0; i < m.slims.size(); ++i) EXPECT_FALSE(r.slims[i].max_push.has_value()) << i;
    ASSERT_EQ(r.slim_hierarchy.others.size(), m.slim_hierarchy.others.size());
    for (std::size_t i = 0; i < m.slim_hierarchy.others.size(); ++i)
      EXPECT_EQ(r.slim_hierarchy.others[i].max_push, m.slim_hierarchy.others[i].max_push) << i;
  }
  std::ifstream in(dir / "p.qxm", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t node = bytes.find("element slim_node"), push = bytes.find("property double max_push");
  EXPECT_NE(push, std::string::npos);
  EXPECT_GT(push, node);  // only the element whose balls have one
  m.slim_hierarchy.others[0].max_push = 0.0;
  EXPECT_THROW(write_model(m, dir / "bad.qxm"), InvalidInput);
}

TEST(ModelIo, HierarchyRoundTrips) {
  ScratchDir dir("qxm2");
  Model m = sample_hierarchy();
  m.metadata["producer"] = "test";
  write_model(m, dir / "h.qxm", {.encoding = ModelEncoding::full});
  std::ifstream in(dir / "h.qxm", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(bytes.find("comment quadrix-format 4\ncomment quadrix-encoding double\n"), std::string::npos);
  EXPECT_NE(bytes.find("element slim 4\n"), std::string::npos);
  EXPECT_NE(bytes.find("element slim_node 3\n"), std::string::npos);
  EXPECT_NE(bytes.find("property int parent\nproperty double error\n"), std::string::npos);
  const Model r = read_model(dir / "h.qxm");
  expect_same_primitives(m, r);
  ASSERT_EQ(r.slim_hierarchy.others.size(), 3u);
  Model mo, ro;  // the interior balls, compared the same way
  mo.slims = m.slim_hierarchy.others;
  ro.slims = r.slim_hierarchy.others;
  expect_same_primitives(mo, ro);
  EXPECT_EQ(r.slim_hierarchy.parent, m.slim_hierarchy.parent);
  EXPECT_EQ(r.slim_hierarchy.error, m.slim_hierarchy.error);  // doubles, bit for bit
  EXPECT_EQ(without_bbox(r.metadata), m.metadata);

  // Corrupt hierarchies are refused with the element, row and byte.
  Model bad = m;
  bad.slim_hierarchy.parent[2] = 9;
  EXPECT_THROW(write_model(bad, dir / "bad.qxm"), InvalidInput);
  std::string cyc = bytes;
  // Row 6 (slim_node row 2) is the root: make its parent 5, closing 5 → 6 → 5.
  const std::size_t body = cyc.find("end_header\n") + 11;
  const std::size_t slim_row = 14 * 8 + 4 * 8 + 3 + 4 + 8;  // with clip and colour
  const std::size_t node_row = 14 * 8 + 3 + 4 + 8;              // colour, no clip
  const std::size_t at = body + 4 * slim_row + 2 * node_row + 14 * 8 + 3;
  std::int32_t old = 0;
  std::memcpy(&old, cyc.data() + at, 4);
  ASSERT_EQ(old, -1);
  const std::int32_t five = 5;
  std::memcpy(cyc.data() + at, &five, 4);
  write_bytes(dir / "cycle.qxm", cyc);
  try {
    read_model(dir / "cycle.qxm");
    ADD_FAILURE() << "cycle accepted";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("cycle.qxm: element 'slim_node' row"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("property 'parent' at byte"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cycle"), std::string::npos) << e.what();
  }
  std::string self = bytes;
  const std::int32_t six = 6;
  std::memcpy(self.data() + at, &six, 4);
  write_bytes(dir / "self.qxm", self);
  try {
    read_model(dir / "self.qxm");
    ADD_FAILURE() << "self parent accepted";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("element 'slim_node' row 2 property 'parent' at byte " + std::to_string(at) +
                                           ": parent 6 is the ball itself"),
              std::string::npos)
        << e.what();
  }
}

// ---------------------------------------------------------------- implicit surfaces

Model implicit_model() {
  Model m = make_sample_model(true);
  // Parameters named out of alphabetical order: the file keeps the expression's order (b, a).
  m.implicits.push_back({"b*x^2 + a*y^2 + z^2 - 1", {{"a", 0.1 + 1e-17}, {"b", 2.0 / 3.0}},
                         {Eigen::Vector3d(-1, -2, -3), Eigen::Vector3d(1, 2, 3.5)}, Rgb{10, 200, 30}});
  // Longer than a uchar list count holds.
  std::string long_expr = "x^2 + y^2 + z^2";
  while (long_expr.size() < 400) long_expr += " + 0.001*sin(x)";
  m.implicits.push_back({long_expr + " - 1", {}, {Eigen::Vector3d::Constant(-1.5), Eigen::Vector3d::Constant(1.5)}, {}});
  return m;
}

void expect_same_implicits(const Model& a, const Model& b) {
  ASSERT_EQ(a.implicits.size(), b.implicits.size());
  for (std::size_t i = 0; i < a.implicits.size(); ++i) {
    const ImplicitSurface &x = a.implicits[i], &y = b.implicits[i];
    EXPECT_EQ(x.expression, y.expression) << "implicit " << i;
    ASSERT_EQ(x.parameters.size(), y.parameters.size()) << "implicit " << i;
    for (const auto& [k, v] : x.parameters) EXPECT_TRUE(y.parameters.count(k) && same_bits(v, y.parameters.at(k))) << k;
    EXPECT_TRUE(same_bits(x.bounds.min, y.bounds.min) && same_bits(x.bounds.max, y.bounds.max)) << "implicit " << i;
    // As for the other kinds, a row without a colour in a file with colours reads back as black.
    EXPECT_EQ(y.colour, x.colour.value_or(Rgb{0, 0, 0})) << "implicit " << i;
  }
}

TEST(ModelIo, ImplicitSurfacesRoundTripBesideOtherPrimitives) {
  ScratchDir dir("model-io");
  const Model m = implicit_model();
  write_model(m, dir / "m.qxm", {.encoding = ModelEncoding::full});  // bit-exact: the lossless encoding
  const std::string bytes = test::read_bytes(dir / "m.qxm");
  const std::string header = bytes.substr(0, bytes.find("end_header"));
  EXPECT_NE(header.find("element implicit 2\nproperty list uint uchar expression\n"
                        "property list uchar double parameters\nproperty double min_x\n"),
            std::string::npos) << header;
  const Model r = read_model(dir / "m.qxm");
  expect_same_primitives(m, r);
  expect_same_implicits(m, r);
  // The bounding box comment covers the implicits' boxes.
  EXPECT_LE(bounds(r).min.z(), -3.0);
  // Parameter values in the file follow the expression's order: b (2/3) before a.
  double first = 0;
  const std::size_t at = bytes.find("b*x^2") + std::string("b*x^2 + a*y^2 + z^2 - 1").size();
  ASSERT_EQ(static_cast<unsigned char>(bytes[at]), 2);
  std::memcpy(&first, bytes.data() + at + 1, 8);
  EXPECT_EQ(first, 2.0 / 3.0);
}

TEST(ModelIo, ImplicitOnlyAsciiModelWithExtraListsLoads) {
  ScratchDir dir("model-io");
  const std::string expr = "x^2 + y^2 - r";
  std::string row = std::to_string(expr.size());
  for (char c : expr) row += " " + std::to_string(int(c));
  write_bytes(dir / "a.qxm",
              "ply\nformat ascii 1.0\ncomment quadrix-format 2\nelement implicit 2\n"
              "property list ushort uchar expression\nproperty list uchar int tags\n"
              "property list int double parameters\nproperty float min_x\nproperty double min_y\n"
              "property double min_z\nproperty double max_x\nproperty double max_y\nproperty double max_z\n"
              "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n" +
                  row + " 3 7 8 9 1 0.25 -1 -1 -1 1 1 1 1 2 3\n" + row + " 0 1 4 -2 -2 -2 2 2 2 4 5 6\n");
  const Model r = read_model(dir / "a.qxm");
  ASSERT_EQ(r.implicits.size(), 2u);
  EXPECT_EQ(r.implicits[1].expression, expr);
  EXPECT_EQ(r.implicits[0].parameters.at("r"), 0.25);
  EXPECT_EQ(r.implicits[1].parameters.at("r"), 4.0);
  EXPECT_EQ(r.implicits[1].bounds.max, Eigen::Vector3d(2, 2, 2));
  EXPECT_EQ(r.implicits[1].colour, (Rgb{4, 5, 6}));
}

TEST(ModelIo, BadImplicitRowsNameRowAndColumn) {
  ScratchDir dir("model-io");
  const auto message = [&](Model m) {
    // Written through a document without the writer's checks: the broken row is the second.
    std::string expr = m.implicits[1].expression;
    std::string text =
        "ply\nformat ascii 1.0\ncomment quadrix-format 2\nelement implicit 2\n"
        "property list uchar uchar expression\nproperty list uchar double parameters\n"
        "property double min_x\nproperty double min_y\nproperty double min_z\n"
        "property double max_x\nproperty double max_y\nproperty double max_z\nend_header\n"
        "1 120 0 -1 -1 -1 1 1 1\n";
    text += std::to_string(expr.size());
    for (char c : expr) text += " " + std::to_string(int(static_cast<unsigned char>(c)));
    text += " " + std::to_string(m.implicits[1].parameters.size());
    for (const auto& [k, v] : m.implicits[1].parameters) text += " " + std::to_string(v);
    const Box3& b = m.implicits[1].bounds;
    text += fmt::format(" {} {} {} {} {} {}\n", b.min.x(), b.min.y(), b.min.z(), b.max.x(), b.max.y(), b.max.z());
    write_bytes(dir / "bad.qxm", text);
    try {
      read_model(dir / "bad.qxm");
    } catch (const FormatError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const Box3 cube{Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1)};
  const auto two = [&](std::string e, std::map<std::string, double> p, Box3 b) {
    Model m;
    m.implicits.push_back({"x", {}, cube, {}});
    m.implicits.push_back({std::move(e), std::move(p), b, {}});
    return m;
  };
  std::string msg = message(two("x^2 + (y", {}, cube));
  EXPECT_NE(msg.find("element 'implicit' row 1 property 'expression'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("column 9"), std::string::npos) << msg;
  msg = message(two("a*x - b", {{"a", 1}}, cube));
  EXPECT_NE(msg.find("1 values for the 2 parameters of 'a*x - b' (a, b)"), std::string::npos) << msg;
  msg = message(two("x - 1", {}, {Eigen::Vector3d(-1, 2, -1), Eigen::Vector3d(1, 2, 1)}));
  EXPECT_NE(msg.find("property 'max_y'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("the box is empty"), std::string::npos) << msg;
}

TEST(ModelIo, WriterRefusesUnusableImplicits) {
  ScratchDir dir("model-io");
  const Box3 cube{Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1)};
  for (const ImplicitSurface& s : {ImplicitSurface{"x^2 - r", {}, cube, {}}, ImplicitSurface{"x^2 - 1", {{"r", 1}}, cube, {}},
                                   ImplicitSurface{"x^2 +", {}, cube, {}}, ImplicitSurface{"x - 1", {}, Box3{}, {}}}) {
    Model m;
    m.implicits.push_back(s);
    EXPECT_THROW(write_model(m, dir / "m.qxm"), InvalidInput) << s.expression;
    EXPECT_FALSE(std::filesystem::exists(dir / "m.qxm"));
  }
}

TEST(ModelIo, Revision1FilesStillLoad) {
  ScratchDir dir("qxm1");
  // A revision-1 file as the previous writer made it: no parent/error, no slim_node.
  const std::string rev1 =
      "ply\nformat ascii 1.0\ncomment quadrix-format 1\ncomment producer old\nelement slim 1\n"
      "property double x\nproperty double y\nproperty double z\nproperty double radius\n"
      "property double k_xx\nproperty double k_yy\nproperty double k_zz\nproperty double k_xy\n"
      "property double k_yz\nproperty double k_zx\nproperty double k_x\nproperty double k_y\n"
      "property double k_z\nproperty double k_1\nend_header\n1 2 3 0.5 1 1 1 0 0 0 0 0 0 -0.25\n";
  write_bytes(dir / "old.qxm", rev1);
  const Model m = read_model(dir / "old.qxm");
  ASSERT_EQ(m.slims.size(), 1u);
  EXPECT_EQ(m.slims[0].centre, Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(m.slim_hierarchy.empty());
  EXPECT_EQ(m.metadata.at("producer"), "old");
  // slim_node without the hierarchy columns on slim is refused.
  std::string orphan = rev1;
  orphan.replace(orphan.find("end_header"), 10,
                 "element slim_node 0\nproperty double x\nend_header");
  write_bytes(dir / "orphan.qxm", orphan);
  EXPECT_THROW(read_model(dir / "orphan.qxm"), FormatError);
}

// ------------------------------------------------------------------ the real .slim2t

const std::filesystem::path kBunnySlim = std::filesystem::path(QUADRIX_DATASETS) / "slim/bunny_mesh2slim.slim2t";
const std::filesystem::path kBunnyMesh = std::filesystem::path(QUADRIX_DATASETS) / "meshes/bunny.ply";

constexpr std::size_t kBunnyLevels = 21;  // measured
// Measured (8 views at 128²): distance p99 0.010, p99.9 0.045 (size 10); depth gap p50 1.1e-4,
// p99 0.081; pixels hit by one surface only: 0.9 % (mesh only) and 0.5 % (SLIM only), silhouettes.
constexpr double kBunnyP99Distance = 0.02;
constexpr double kBunnyP50DepthGap = 1e-3;  // the far side (a flipped model) would be units away
constexpr double kBunnyP99DepthGap = 0.15;
constexpr double kBunnyOneSidedShare = 0.015;  // the longest root-to-leaf path, counted in balls

/// Closest point of triangle abc to p (Ericson, Real-Time Collision Detection §5.1.5).
Eigen::Vector3d closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

/// Triangles for nearest-point and first-hit queries: a BVH and a uniform grid of cell h.
struct MeshQueries {
  std::vector<std::array<Eigen::Vector3d, 3>> tris;
  Bvh bvh;
  double h = 0.1;
  std::map<std::array<int, 3>, std::vector<int>> grid;

  explicit MeshQueries(std::vector<std::array<Eigen::Vector3d, 3>> t) : tris(std::move(t)) {
    std::vector<Box3> boxes(tris.size());
    for (std::size_t i = 0; i < tris.size(); ++i) {
      for (const auto& v : tris[i]) boxes[i].extend(v);
      const auto lo = cell(boxes[i].min), hi = cell(boxes[i].max);
      for (int x = lo[0]; x <= hi[0]; ++x)
        for (int y = lo[1]; y <= hi[1]; ++y)
          for (int z = lo[2]; z <= hi[2]; ++z) grid[{x, y, z}].push_back(static_cast<int>(i));
    }
    bvh = Bvh(boxes);
  }
  std::array<int, 3> cell(const Eigen::Vector3d& p) const {
    return {static_cast<int>(std::floor(p.x() / h)), static_cast<int>(std::floor(p.y() / h)),
            static_cast<int>(std::floor(p.z() / h))};
  }
  /// Exact distance to the nearest triangle (rings of cells until the ring bounds the answer).
  double distance(const Eigen::Vector3d& p) const {
    const auto c = cell(p);
    double best = std::numeric_limits<double>::infinity();
    for (int k = 1; k < 200; ++k) {
      for (int x = -k; x <= k; ++x)
        for (int y = -k; y <= k; ++y)
          for (int z = -k; z <= k; ++z) {
            if (std::max({std::abs(x), std::abs(y), std::abs(z)}) < k - 1 && k > 1) continue;
            const auto it = grid.find({c[0] + x, c[1] + y, c[2] + z});
            if (it == grid.end()) continue;
            for (int t : it->second) {
              const auto& tr = tris[static_cast<std::size_t>(t)];
              best = std::min(best, (p - closest_on_triangle(p, tr[0], tr[1], tr[2])).norm());
            }
          }
      if (best <= (k - 1) * h) return best;  // everything within (k − 1)·h has been visited
    }
    return best;
  }
  /// Distance to the first triangle along the ray (Möller–Trumbore), or +inf.
  double first_hit(const Ray& ray) const {
    double best = std::numeric_limits<double>::infinity();
    bvh.traverse(ray, 0.0, [&] { return best; }, [&](std::uint32_t i) {
      const auto& tr = tris[i];
      const Eigen::Vector3d e1 = tr[1] - tr[0], e2 = tr[2] - tr[0], pv = ray.dir.cross(e2);
      const double det = e1.dot(pv);
      if (std::abs(det) < 1e-300) return;
      const Eigen::Vector3d tv = ray.origin - tr[0];
      const double u = tv.dot(pv) / det;
      if (u < 0 || u > 1) return;
      const Eigen::Vector3d q = tv.cross(e1);
      const double v = ray.dir.dot(q) / det, t = e2.dot(q) / det;
      if (v < 0 || u + v > 1 || t <= 0) return;
      best = std::min(best, t);
    });
    return best;
  }
};

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

TEST(Slim2tReal, LeavesBlendToTheBunnyMesh) {
  if (!std::filesystem::exists(kBunnySlim) || !std::filesystem::exists(kBunnyMesh))
    GTEST_SKIP() << "data set not found: " << kBunnySlim.string() << " or " << kBunnyMesh.string();
  const Model m = read_model(kBunnySlim);
  // bunny.ply in mesh2slim's frame: centred on its bounding-box centre, largest box side 10.
  const PolygonMesh mesh = read_mesh(kBunnyMesh);
  Box3 box;
  for (const auto& v : mesh.vertices) box.extend(v);
  const double scale = 10.0 / (box.max - box.min).maxCoeff();
  std::vector<std::array<Eigen::Vector3d, 3>> tris;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const auto face = mesh.face(f);
    ASSERT_EQ(face.size(), 3u);
    std::array<Eigen::Vector3d, 3> t;
    for (int k = 0; k < 3; ++k) t[k] = (mesh.vertices[static_cast<std::size_t>(face[k])] - box.centre()) * scale;
    tris.push_back(t);
  }
  const MeshQueries queries(std::move(tris));
  const ReferenceScene scene(m);
  std::vector<double> distances, depth_gaps;
  std::size_t mesh_pixels = 0, slim_pixels = 0, holes = 0, extra = 0;
  for (const auto& [az, el] : std::vector<std::pair<double, double>>{
           {0, 10}, {60, 20}, {120, -10}, {180, 30}, {240, 0}, {300, -30}, {90, 80}, {30, -80}}) {
    const Camera cam = frame_box(bounds(m), {.azimuth_deg = az, .elevation_deg = el, .width = 128, .height = 128});
    const ReferenceImage img = render_reference(scene, cam);
    for (int y = 0; y < cam.height; ++y)
      for (int x = 0; x < cam.width; ++x) {
        const std::size_t px = static_cast<std::size_t>(y) * static_cast<std::size_t>(cam.width) +
                               static_cast<std::size_t>(x);
        const Ray ray = cam.pixel_ray(x + 0.5, y + 0.5);
        const double t_mesh = queries.first_hit(ray);
        const bool has_mesh = std::isfinite(t_mesh), has_slim = img.coverage[px] != 0;
        mesh_pixels += has_mesh;
        slim_pixels += has_slim;
        holes += has_mesh && !has_slim;
        extra += has_slim && !has_mesh;
        if (!has_slim) continue;
        const double t = img.distance[px];
        distances.push_back(queries.distance(ray.at(t)));
        if (has_mesh) depth_gaps.push_back(std::abs(t - t_mesh));
      }
  }
  const double p50 = percentile(distances, 0.5), p99 = percentile(distances, 0.99),
               p999 = percentile(distances, 0.999), worst = percentile(distances, 1.0);
  const double gap99 = percentile(depth_gaps, 0.99);
  std::printf("[   INFO   ] %zu hit pixels (mesh %zu): distance to the mesh p50 %.3g p99 %.3g p99.9 %.3g max %.3g "
              "(model size 10); first-hit depth gap p50 %.3g p99 %.3g; holes %zu, outside the mesh %zu\n",
              slim_pixels, mesh_pixels, p50, p99, p999, worst, percentile(depth_gaps, 0.5), gap99, holes, extra);
  EXPECT_LT(p99, kBunnyP99Distance);
  EXPECT_LT(percentile(depth_gaps, 0.5), kBunnyP50DepthGap);
  EXPECT_LT(gap99, kBunnyP99DepthGap);
  EXPECT_LT(static_cast<double>(holes), kBunnyOneSidedShare * static_cast<double>(mesh_pixels));
  EXPECT_LT(static_cast<double>(extra), kBunnyOneSidedShare * static_cast<double>(mesh_pixels));
}

TEST(Slim2tReal, BunnyHierarchyLoads) {
  if (!std::filesystem::exists(kBunnySlim)) GTEST_SKIP() << "data set not found: " << kBunnySlim.string();
  const Model m = read_model(kBunnySlim);
  EXPECT_EQ(m.slims.size(), 69451u);  // one leaf per triangle of bunny.ply
  const SlimHierarchy& h = m.slim_hierarchy;
  EXPECT_EQ(h.size(), 138901u);
  EXPECT_EQ(h.others.size(), 69450u);
  EXPECT_EQ(validate_slim_hierarchy(m), "");
  const SlimHierarchyStats st = slim_hierarchy_stats(m);
  EXPECT_EQ(st.leaves, 69451u);
  EXPECT_EQ(st.interior, 69450u);
  EXPECT_EQ(st.roots, 1u);
  EXPECT_EQ(st.levels, kBunnyLevels);
  EXPECT_EQ(st.min_error, 0.0);
  EXPECT_EQ(st.max_error, static_cast<double>(42736.43359375f));
  for (std::size_t i = 0; i < m.slims.size(); ++i) ASSERT_EQ(h.error[i], 0.0) << "leaf " << i;
  // Errors grow towards the root, so a cut is the set the definition names.
  for (std::size_t i = 0; i < h.size(); ++i)
    if (h.parent[i] >= 0) {
      ASSERT_GE(h.error[static_cast<std::size_t>(h.parent[i])], h.error[i]) << "ball " << i;
    }
  EXPECT_EQ(select_slim_cut(m, 0.0).size(), 69451u);
  EXPECT_EQ(select_slim_cut(m, st.max_error), (std::vector<std::int32_t>{static_cast<std::int32_t>(
                                                  std::find(h.parent.begin(), h.parent.end(), -1) - h.parent.begin())}));
  for (const double threshold : {1e-3, 1.0, 100.0}) {
    const auto cut = select_slim_cut(m, threshold);
    std::vector<int> covered(h.size(), 0);
    for (std::int32_t b : cut) {
      EXPECT_LE(h.error[static_cast<std::size_t>(b)], threshold);
      const std::int32_t p = h.parent[static_cast<std::size_t>(b)];
      if (p >= 0) {
        EXPECT_GT(h.error[static_cast<std::size_t>(p)], threshold);
      }
      covered[static_cast<std::size_t>(b)] = 1;
    }
    // Every leaf lies under exactly one ball of the cut.
    for (std::size_t leaf = 0; leaf < m.slims.size(); ++leaf) {
      int under = 0;
      for (std::int64_t a = static_cast<std::int64_t>(leaf); a >= 0; a = h.parent[static_cast<std::size_t>(a)])
        under += covered[static_cast<std::size_t>(a)];
      ASSERT_EQ(under, 1) << "leaf " << leaf << " threshold " << threshold;
    }
    std::printf("[   INFO   ] cut at error %g: %zu balls\n", threshold, cut.size());
  }
  // The file is unoriented (degree −2); every ball pointed inwards and was flipped.
  EXPECT_EQ(m.metadata.at("slim2t_degree"), "-2");
  EXPECT_NE(m.metadata.at("slim2t_orientation").find("every ball was flipped"), std::string::npos)
      << m.metadata.at("slim2t_orientation");
  std::printf("[   INFO   ] %s\n", m.metadata.at("slim2t_orientation").c_str());
}

}  // namespace
}  // namespace quadrix
