// The one world-coordinate limit (core/limits.h) and the one degeneracy limit for tetrahedra
// (core/bounds.h), as every reader and writer applies them: values past them are refused with a
// message naming the file and the limit, never turned into an empty model or an infinite box.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>

#include "core/bounds.h"
#include "core/error.h"
#include "core/io/io.h"
#include "core/limits.h"
#include "core/model_io.h"
#include "tests/core/malformed_corpus.h"

namespace quadrix {
namespace {

using Eigen::Vector3d;
using test::ScratchDir;

void put(const std::filesystem::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

template <typename E, typename F>
void expect_refused(F&& f, const std::string& file, const std::string& fragment) {
  try {
    f();
    ADD_FAILURE() << "accepted; expected a refusal naming '" << fragment << "'";
  } catch (const E& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(file), std::string::npos) << m;
    EXPECT_NE(m.find(fragment), std::string::npos) << m;
  }
}

TEST(WorldLimit, BoundaryIsInclusiveAndNanIsOutside) {
  EXPECT_TRUE(is_world_value(kMaxWorldCoordinate));
  EXPECT_TRUE(is_world_value(-kMaxWorldCoordinate));
  EXPECT_FALSE(is_world_value(std::nextafter(kMaxWorldCoordinate, 1e300)));
  EXPECT_FALSE(is_world_value(std::numeric_limits<double>::quiet_NaN()));
  EXPECT_FALSE(is_world_value(-std::numeric_limits<double>::infinity()));
  EXPECT_FALSE(is_world_point(Vector3d(0, 1e300, 0)));
  EXPECT_THROW(check_world_point(Vector3d(0, 0, 1e13), "centre"), InvalidInput);
  EXPECT_NO_THROW(check_world_point(Vector3d(0, 0, 1e12), "centre"));
}

TEST(WorldLimit, ReadersRefuseFiniteCoordinatesPastIt) {
  ScratchDir dir("limits");
  std::string xyz;
  for (int i = 0; i < 12; ++i) xyz += std::to_string(i) + " " + std::to_string(i * i % 7) + " 1\n";
  put(dir / "ok.xyz", xyz);
  EXPECT_EQ(read_points(dir / "ok.xyz").points.size(), 12u);
  put(dir / "far.xyz", xyz + "1e300 0 0\n");
  expect_refused<FormatError>([&] { read_points(dir / "far.xyz"); }, "far.xyz:13:", "largest world coordinate");
  put(dir / "far.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 2e12 0\n3 0 1 2\n");
  expect_refused<FormatError>([&] { read_mesh(dir / "far.off"); }, "far.off:5:", "largest world coordinate");
}

TEST(WorldLimit, ModelsPastItAreNeitherWrittenNorRead) {
  ScratchDir dir("limits");
  Model m;
  SlimPatch s;
  s.local = Quadric::sphere(Vector3d::Zero(), 0.5);
  m.slims.push_back(s);
  s.centre = Vector3d(3, 0, 0);
  m.slims.push_back(s);
  write_model(m, dir / "ok.qxm");
  EXPECT_EQ(read_model(dir / "ok.qxm").slims.size(), 2u);
  m.slims[1].centre.x() = 1e300;  // "a model scaled 1e300": finite, but its diagonal would be inf
  expect_refused<InvalidInput>([&] { write_model(m, dir / "far.qxm"); }, "far.qxm", "largest world coordinate");
  EXPECT_FALSE(std::filesystem::exists(dir / "far.qxm"));
  m.slims[1].centre.x() = 3;
  m.slims[1].radius = 2e12;
  expect_refused<InvalidInput>([&] { write_model(m, dir / "big.qxm"); }, "big.qxm", "largest world coordinate");
  // The reader: the same file with one centre moved to 1e300 by hand.
  std::string bytes;
  {
    std::ifstream in(dir / "ok.qxm", std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const auto body = bytes.find("end_header\n") + 11;
  const double far = 1e300;
  std::memcpy(bytes.data() + body, &far, 8);  // slim 0, centre x (float64 little-endian)
  put(dir / "scaled.qxm", bytes);
  expect_refused<FormatError>([&] { read_model(dir / "scaled.qxm"); }, "scaled.qxm", "largest world coordinate");
}

// One degeneracy rule: a tetrahedron just thicker than the limit passes every check, one just
// thinner fails every one (the .qxm reader and the in-memory test agree).
TEST(DegenerateTetrahedron, OneLimitEverywhere) {
  const auto tet = [](double h) {
    return std::array<Vector3d, 4>{Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0), Vector3d(0.2, 0.2, h)};
  };
  // Longest edge √2 (between (1,0,0) and (0,1,0)); 6V = h.
  const double L3 = std::pow(std::sqrt(2.0), 3);
  EXPECT_FALSE(is_degenerate_tetrahedron(tet(2 * kDegenerateTetrahedron * L3)));
  EXPECT_TRUE(is_degenerate_tetrahedron(tet(0.5 * kDegenerateTetrahedron * L3)));
  EXPECT_TRUE(is_degenerate_tetrahedron(tet(0)));

  ScratchDir dir("limits");
  for (const double factor : {2.0, 0.5}) {
    Model m;
    m.tets.push_back(TetPatch::from_world(tet(factor * kDegenerateTetrahedron * L3), Quadric::sphere(Vector3d::Zero(), 0.3)));
    write_model(m, dir / "t.qxm");
    if (factor > 1)
      EXPECT_EQ(read_model(dir / "t.qxm").tets.size(), 1u);
    else
      expect_refused<FormatError>([&] { read_model(dir / "t.qxm"); }, "t.qxm", "degenerate tetrahedron");
  }
}

// The drawable extent: an absolute floor (kMinWorldSize) and one relative to the largest
// coordinate (kMinRelativeExtent); empty boxes pass; tiny extents are measured without squares.
TEST(DrawableExtent, AbsoluteAndRelativeFloors) {
  const auto check = [](const Vector3d& lo, const Vector3d& hi) { check_drawable_extent(lo, hi, "m.qxm"); };
  EXPECT_NO_THROW(check(Vector3d::Zero(), Vector3d(2 * kMinWorldSize, 0, 0)));
  expect_refused<InvalidInput>([&] { check(Vector3d::Zero(), Vector3d::Constant(0.5 * kMinWorldSize)); }, "m.qxm",
                               "the smallest size Quadrix draws");
  expect_refused<InvalidInput>([&] { check(Vector3d::Zero(), Vector3d::Constant(1e-300)); }, "m.qxm", "1e-300");
  const Vector3d far = Vector3d::Constant(1e12);
  EXPECT_NO_THROW(check(far, far + Vector3d(0, 0, 2 * kMinRelativeExtent * 1e12)));
  expect_refused<InvalidInput>([&] { check(far, far + Vector3d(0, 0, 0.5 * kMinRelativeExtent * 1e12)); }, "m.qxm",
                               "of its largest coordinate 1e+12");
  expect_refused<InvalidInput>([&] { check(-far, -far + Vector3d::Constant(1.0)); }, "m.qxm", "largest coordinate");
  EXPECT_NO_THROW(check(Vector3d::Constant(1), Vector3d::Constant(-1)));  // empty
}

}  // namespace
}  // namespace quadrix
