// The mesher's mesh → surface measure with its memo: a sample answered from the memo has the
// figure a trace would give, so a mesh changed in one part is traced only there.
#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "convert/mesh_measure.h"
#include "convert/to_mesh.h"
#include "core/reference.h"
#include "core/slim.h"
#include "core/synth.h"

using namespace quadrix;

TEST(MeshMeasure, MemoGivesTheWholeMeasureWhereOnlyOnePartChanged) {
  const Model model = synth_model("slim-sphere");
  const double bound = 4e-3, reach = 0.04;
  const PolygonMesh mesh =
      mesh_model(model, {.max_error = bound, .max_refinements = 0, .local_refinements = 0, .grid_refinements = 0,
                         .progress = {}})
          .mesh;
  ASSERT_GT(mesh.face_count(), 1000u);
  const ReferenceScene scene(model);
  TraceOptions trace;
  trace.slim = slim_blend_of(model);
  SampleMemo memo;
  const MeshDistance first = mesh_to_surface(scene, trace, mesh, reach, bound, nullptr, &memo);
  EXPECT_EQ(memo.traced(), first.samples);
  EXPECT_EQ(memo.reused(), 0u);

  // One cap pushed out beyond the bound: its samples, and those whose vertex normals its move
  // turned, change; the rest are as before.
  PolygonMesh changed = mesh;
  for (Eigen::Vector3d& p : changed.vertices)
    if (p.x() > 0.8) p *= 1.0 + 5.0 * bound;
  BeyondSamples with_memo, traced_where;
  const MeshDistance a = mesh_to_surface(scene, trace, changed, reach, bound, &with_memo, &memo);
  const MeshDistance b = mesh_to_surface(scene, trace, changed, reach, bound, &traced_where);
  ASSERT_GT(b.beyond, 0u) << "the moved cap should be beyond the bound";
  EXPECT_EQ(a.max, b.max);
  EXPECT_EQ(a.rms, b.rms);
  EXPECT_EQ(a.p99, b.p99);
  EXPECT_EQ(a.samples, b.samples);
  EXPECT_EQ(a.misses, b.misses);
  EXPECT_EQ(a.beyond, b.beyond);
  EXPECT_EQ(with_memo.faces, traced_where.faces);
  EXPECT_EQ(with_memo.vertices, traced_where.vertices);
  const std::size_t traced_again = memo.traced() - first.samples;
  std::cout << "samples " << a.samples << ", traced again " << traced_again << ", from the memo " << memo.reused() << "\n";
  EXPECT_GT(traced_again, 0u);
  EXPECT_LT(traced_again * 4, a.samples) << "only the changed part should be traced again";
  EXPECT_EQ(traced_again + memo.reused(), a.samples);

  // Another reach: nothing measured before holds.
  const MeshDistance c = mesh_to_surface(scene, trace, changed, 2 * reach, bound, nullptr, &memo);
  EXPECT_EQ(memo.traced(), first.samples + traced_again + c.samples);
}

// Two fans at one vertex (a bowtie: two triangles touching at a corner, and a closed fan of four
// beside them) split into one vertex per fan, with the same position, colour and normal; faces
// sharing an edge stay on one vertex.
TEST(MeshMeasure, PinchedVerticesSplitIntoOneVertexPerFan) {
  PolygonMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}, {0, 1, 0}};
  m.colours = {{1, 2, 3}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  m.normals.assign(6, Eigen::Vector3d::UnitZ());
  m.add_face(std::array<int, 3>{0, 1, 2});
  m.add_face(std::array<int, 3>{0, 2, 5});  // shares edge 0–2 with the first: the same fan
  m.add_face(std::array<int, 3>{0, 3, 4});  // touches the others at vertex 0 only
  PolygonMesh split = m;
  EXPECT_EQ(split_pinched_vertices(split), 1u);
  ASSERT_EQ(split.vertices.size(), 7u);
  EXPECT_EQ(split.vertices[6], m.vertices[0]);
  EXPECT_EQ(split.colours[6], m.colours[0]);
  EXPECT_EQ(split.normals[6], m.normals[0]);
  EXPECT_EQ(split.face(0)[0], split.face(1)[0]);
  EXPECT_NE(split.face(0)[0], split.face(2)[0]);
  EXPECT_EQ(split_pinched_vertices(split), 0u) << "nothing pinched is left";
  // A closed octahedron has nothing to split.
  PolygonMesh o;
  o.vertices = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const auto& f : std::vector<std::array<int, 3>>{{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                                                        {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}})
    o.add_face(f);
  EXPECT_EQ(split_pinched_vertices(o), 0u);
  EXPECT_EQ(o.vertices.size(), 6u);
}
