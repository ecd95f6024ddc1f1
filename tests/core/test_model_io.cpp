#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <sstream>

#include "core/error.h"
#include "core/model_io.h"
#include "core/ply.h"
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
    ASSERT_EQ(x.clip.has_value(), y.clip.has_value()) << "slim " << i;
    if (x.clip) {
      EXPECT_TRUE(same_bits(x.clip->n, y.clip->n) && same_bits(x.clip->d, y.clip->d)) << "slim " << i;
    }
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
  ASSERT_TRUE(m.slims[1].clip == std::nullopt && m.slims[0].clip.has_value());  // mixed clip planes
  write_model(m, dir / "m.qxm");
  const Model r = read_model(dir / "m.qxm");
  expect_same_primitives(m, r);
  EXPECT_EQ(without_bbox(r.metadata), m.metadata);
}

TEST(ModelIo, RoundTripIsBitExactWithoutOptionalProperties) {
  ScratchDir dir("model-io");
  const Model m = make_sample_model(false);
  write_model(m, dir / "m.qxm");
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
  EXPECT_EQ(bytes.rfind("ply\nformat binary_little_endian 1.0\ncomment quadrix-format 1\n", 0), 0u);
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
  std::int32_t parent;
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
    const Ball* src[2] = {&balls[2], &balls[3]};
    for (int i = 0; i < 2; ++i) {
      const SlimPatch& s = m.slims[i];
      const Ball& b = *src[i];
      EXPECT_EQ(s.radius, static_cast<double>(b.radius));
      const Eigen::Vector3d c(b.centre[0], b.centre[1], b.centre[2]);
      EXPECT_EQ(s.centre, c);
      QuadricCoefficients k;
      for (int j = 0; j < 10; ++j) k[j] = b.k[j];
      const Quadric original = Quadric::from_coefficients(k);  // local to the centre, unscaled
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
}

}  // namespace
}  // namespace quadrix
