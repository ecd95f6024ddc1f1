#pragma once
/// The mesher's measure of a triangle mesh against the surface the renderer draws (mesh →
/// surface; convert/to_mesh.h uses it, the surface → mesh side is fit/surface_error.h), with a
/// memo of the samples already measured, so that a mesh made again with most of its triangles
/// unchanged is traced only where it changed.
#include <array>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "convert/to_mesh.h"
#include "core/mesh_io.h"
#include "core/reference.h"

namespace quadrix {

/// How vertex_normals weighs a vertex's faces.
enum class NormalWeight {
  area,   ///< by area (the faces' cross products summed)
  angle,  ///< by the face's angle at the vertex (a cube's corner gets the diagonal however its faces are split)
};
/// Vertex normals from the faces around each vertex (unit; zero where a vertex has no face of
/// non-zero area). Angle weights take each face's first three corners.
std::vector<Eigen::Vector3d> vertex_normals(const PolygonMesh& m, NormalWeight weight = NormalWeight::area);

/// Splits each pinched vertex (one whose faces form more than one fan: two sheets touching at a
/// point, a "bowtie") into one vertex per fan, with the same position, colour and normal, so the
/// mesh is a manifold wherever its edges are: programs that walk the mesh's topology (MeshLab's
/// holes and genus, which it calls undefined otherwise) then can. Faces sharing an edge stay one
/// fan (an edge of three or more faces is left as it is). Returns how many vertices were added.
std::size_t split_pinched_vertices(PolygonMesh& m);

/// Where samples lie beyond the bound: per face, its samples' largest distance (its vertices'
/// included; +inf where one met no surface) and which of its edges' midpoints are beyond (bit i:
/// the edge from its vertex i to vertex i + 1 mod 3); per vertex, whether it is beyond.
struct BeyondSamples {
  std::vector<double> faces;
  std::vector<std::uint8_t> edges;
  std::vector<std::uint8_t> vertices;
};

/// Distances already measured, by each sample's exact point and normal, for one reach and bound.
/// A sample's distance depends on nothing else (the scene and trace options are the caller's to
/// keep the same), so a memo hit gives the figure a new trace would.
class SampleMemo {
 public:
  /// Empties the memo unless its samples were measured with this reach and bound.
  void use_for(double reach, double bound);
  /// The distance measured at (p, n) (−1: no line met a surface), or null. Safe beside other finds.
  const double* find(const Eigen::Vector3d& p, const Eigen::Vector3d& n) const;
  void insert(const Eigen::Vector3d& p, const Eigen::Vector3d& n, double distance);
  void count(std::size_t traced, std::size_t reused) { traced_ += traced, reused_ += reused; }
  std::size_t traced() const { return traced_; }  ///< samples measured by tracing so far
  std::size_t reused() const { return reused_; }  ///< samples answered from the memo so far

 private:
  using Key = std::array<double, 6>;  // point, normal
  struct KeyHash {
    std::size_t operator()(const Key& k) const;
  };
  double reach_ = -1, bound_ = -1;
  std::unordered_map<Key, double, KeyHash> distance_;
  std::size_t traced_ = 0, reused_ = 0;
};

/// Mesh → drawn surface at every vertex, edge midpoint and face centroid: the nearest surface the
/// CPU reference draws along the sample's normal line (both ways, within reach), and where that
/// is beyond the bound along the 13 lines towards its grid neighbours (nearest_along_lines), and
/// where none meets it, along parallel lines around it (each bounding the distance by its own plus
/// the offset). `where` (optional) gets the samples beyond the bound per face and vertex; `memo`
/// (optional) answers samples measured before with the same reach and bound, and keeps the new
/// ones (it is emptied when reach or bound differ from its own).
MeshDistance mesh_to_surface(const ReferenceScene& scene, const TraceOptions& trace, const PolygonMesh& m, double reach,
                             double bound, BeyondSamples* where = nullptr, SampleMemo* memo = nullptr);

}  // namespace quadrix
