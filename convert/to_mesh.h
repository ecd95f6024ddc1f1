#pragma once
/// Any model as a triangle mesh within a measured distance of the surface the renderer draws.
///
/// | primitives | how                                                                       |
/// |------------|---------------------------------------------------------------------------|
/// | tetrahedron patches | each tetrahedron first cut (conforming longest-edge bisection) where its lattice would leave its surface by more than half the bound (estimated), then each piece's edgewise subdivision into k³ tetrahedra, marching tetrahedra on its quadric, and, where the tetrahedra tessellate (a volume's cells), the pieces whose faces or nearest drawn points stay beyond the bound cut again in rounds (lattice_rounds); crossings are the quadric's exact roots on the edges; lattice points and crossings welded across shared faces (watertight where neighbours agree in sign) |
/// | SLIM       | marching tetrahedra (Kuhn split) on a grid whose nodes are labelled inside/outside by the per-ray blend itself (core/slim.h): the crossings of the grid lines through each node, majority of the three axes, the blended Taubin distance Σwᵢdᵢ/Σwᵢ deciding split votes; each vertex is where its grid edge enters the blend (else moved onto it along its normal); triangles over holes of the blend are left out (open edges there) |
/// | glyphs     | icospheres (spheres, ellipsoids) and n-gon prisms with capped ends (cylinders), vertices on the surface |
///
/// The error is measured both ways: mesh → surface at every vertex, edge midpoint and face
/// centroid (distance along the sample's normal line, both ways, to what the CPU reference ray
/// caster draws, core/reference.h, and along 13 more lines where that is beyond the bound; an
/// upper bound of the Euclidean distance: see mesh_distance), and surface → mesh from rendered
/// views (fit/surface_error.h). SLIM meshes are first refined locally (longest-edge bisection,
/// and at edges whose midpoint exceeds the bound, without T-junctions where samples exceed it, new vertices moved onto the blend; open
/// edges never cut), then, where samples stay beyond it (parts or gaps thinner than the grid),
/// the grid cells there are cut finer by conforming bisection of their tetrahedra
/// (convert/kuhn_bisection.h: no crack at the seam with the coarse cells) and the SLIM mesh made
/// again, one level per round, while that helps (samples unchanged since an earlier round are not
/// traced again: convert/mesh_measure.h). Where the drawn surface's pixels stay beyond the bound
/// because grazing views see the per-ray blend off where head-on views do, the vertices there move
/// part of the way towards them (convert/between_views.h). Where the mesh is still outside the
/// bound, it is tried two ways and the better kept: as it is, and with its faces still beyond the
/// bound left out (over cracks of the blend, where nothing is drawn; after local refinement also
/// over steps, where two sheets farther apart than the blend's push meet, which a closed mesh
/// bridges), the drawn surface under them measured against what remains; each then gets open
/// sheets where the drawn surface's points beyond the bound lie on one patch's zero set (its rim
/// running on as a fin, or a sheet past a step, which no closed labelling holds), and the opened
/// one's vertices move towards the drawn points still beyond it, as in the view rounds. The resolution doubles until both are within the bound, or
/// until a doubling no longer cuts the share of samples beyond it by 4 (a crack of the blend
/// itself, which no resolution closes) or the larger of the two maxima by half (parts of the
/// drawn surface no closed labelling holds at any resolution: a patch's rim drawn alone, running
/// on as a fin); then the smaller mesh is kept (where only the maximum stayed, the nearer one).
#include <cstddef>
#include <functional>
#include <vector>

#include "core/mesh_io.h"
#include "core/model.h"

namespace quadrix {

struct ToMeshOptions {
  double max_error = 0;           ///< world units; ≤ 0: 1e-3 × the model's bounding-box diagonal
  int max_refinements = 4;        ///< resolution doublings tried after the first mesh
  /// SLIM: rounds of local refinement per grid (longest-edge bisection of the triangles whose
  /// samples exceed the bound, or nearest the drawn surface's points beyond it); 0: off
  int local_refinements = 12;
  /// SLIM: rounds of local grid refinement per resolution (the grid cells holding samples still
  /// beyond the bound after the triangles' refinement cut one level finer, at most to h/8, and
  /// the SLIM mesh made again; a round kept only if it leaves fewer samples beyond and no larger
  /// maximum; none where the triangles' refinement was undone: a cracked blend); 0: off
  int grid_refinements = 2;
  /// Tetrahedra: rounds per resolution cutting the pieces whose lattice faces stay beyond the
  /// bound (each edge about halved per round) and meshing again, while few faces are beyond (at
  /// most 4,096 or 1 in 200) and a round brings the maximum down; 0: off
  int lattice_rounds = 6;
  /// SLIM: rounds moving vertices part of the way towards what grazing views see, where the
  /// per-ray blend shows them the surface off where a head-on view does (convert/between_views.h);
  /// a round kept only if it leaves fewer samples beyond the bound and no larger maximum; 0: off
  int view_rounds = 3;
  /// SLIM: parts of the drawn surface no closed inside/outside labelling holds are made open: a
  /// mesh with the faces still beyond the bound left out (over cracks of the blend, a sample in no
  /// patch's ball; after local refinement also over steps between sheets) is tried beside the
  /// closed one, the better kept; each gets open sheets where the drawn surface's points beyond the
  /// bound lie on one patch's zero set (a rim running on as a fin past where its neighbours'
  /// surface turns), a round kept only if it leaves fewer samples beyond the bound and no larger maximum
  bool open_parts = true;
  /// Each vertex gets the drawn surface's normal there (the CPU reference's shading normal, core/
  /// reference.h, seen along the vertex's own normal), so other programs shade the mesh smoothly
  /// as the renderer does: a SLIM blend's sheets stand off each other by up to its push, and flat
  /// faces following them show facets the blended normals do not. Else the mesh has none.
  bool normals = true;
  /// Overlapping glyphs (a molecule's atoms, and its bonds' tubes) meshed as their union, one
  /// closed surface without the parts hidden inside others (CGAL, convert/mesh_union.h), as the
  /// renderer draws them; else each glyph is its own closed mesh and overlapping ones cross.
  bool union_glyphs = true;
  /// ... up to this many glyphs (the union costs about 28 ms a sphere on these machines: 1tii's
  /// 5,684 atoms 158 s against 34 s glyph by glyph; 4lfq's 1,754 balls and sticks 12 s against
  /// 2 s); more are meshed glyph by glyph
  std::size_t union_max_glyphs = 10'000;
  std::size_t max_triangles = 8'000'000;  ///< no refinement past this many triangles
  double slim_offset = -1;        ///< SLIM blend band; < 0: the model's own (slim_offset_of)
  int views = 8;                  ///< surface → mesh: views (fit/surface_error.h)
  int view_resolution = 256;      ///< surface → mesh: pixels per side of each view
  std::function<void(double)> progress;  ///< fraction done (0..1), roughly
};

/// One direction of the distance between mesh and surface (world units).
struct MeshDistance {
  double max = 0, rms = 0, p99 = 0;
  std::size_t samples = 0;
  std::size_t misses = 0;  ///< mesh → surface: samples whose normal line met no surface nearby
  std::size_t beyond = 0;  ///< samples farther than the bound (misses included)
};

struct ToMeshResult {
  PolygonMesh mesh;                 ///< triangles, counter-clockwise seen from outside; colours if the model has any; normals (ToMeshOptions::normals)
  double bound = 0;                 ///< the max_error aimed at (world units)
  MeshDistance mesh_to_surface;     ///< vertices, edge midpoints, face centroids → drawn surface
  MeshDistance surface_to_mesh;     ///< pixels of the drawn surface → mesh
  std::size_t open_edges = 0;       ///< edges not shared by exactly two triangles (0: watertight)
  int refinements = 0;              ///< doublings used
  int local_rounds = 0;             ///< local refinement rounds used on the last grid
  int grid_rounds = 0;              ///< local grid refinement rounds kept on the last grid
  std::size_t refined_cells = 0;    ///< grid cells asked to be cut finer (the closure cuts some neighbours too)
  int view_rounds = 0;              ///< rounds of moves towards what grazing views see, kept
  int lattice_rounds = 0;           ///< rounds of tetrahedron pieces cut where their faces left the bound, kept
  int fin_rounds = 0;               ///< rounds of open sheets added on patches' rims drawn alone, kept
  std::size_t fin_triangles = 0;    ///< triangles of those sheets
  std::size_t faces_left_out = 0;   ///< SLIM faces left out over cracks and steps of the blend
  bool within = false;              ///< both maxima ≤ bound and no misses
  /// A closed tetrahedron model meshed on one grid (nodes labelled by the drawn surface) instead
  /// of each tetrahedron's own lattice (a skin's slivers; refinements then counts its halvings)
  bool on_grid = false;
  std::size_t normals_from_faces = 0;  ///< vertices whose normal line met no drawn surface nearby: their faces' normal
  std::size_t pinched_vertices_split = 0;  ///< vertices where sheets touched, split into one per fan (convert/mesh_measure.h)
  bool glyph_union = false;              ///< the glyphs were meshed as their union (ToMeshOptions::union_glyphs)
  std::size_t glyph_unions_failed = 0;  ///< ToMeshOptions::union_glyphs: unions CGAL refused (those glyphs left whole, crossing)
  double max_error() const { return std::max(mesh_to_surface.max, surface_to_mesh.max); }
};

/// Whether ToMeshOptions::union_glyphs applies to the model's glyphs: more than one. Spheres and
/// ellipsoids alone are joined pairwise by corefinement; with cylinders (bonds) the glyphs are
/// autorefined as one soup, in a child process (pairwise corefinement crashed on the tubes).
bool unions_glyphs(const Model& model);

/// No partner (bond_halves).
inline constexpr std::size_t kNoPartner = static_cast<std::size_t>(-1);

/// For each glyph, the other half of its bond (convert glyphs: a capped cylinder from each atom to
/// the bond's middle), else kNoPartner: two cylinders of one radius whose far ends meet (within
/// 1e-5 of their length: a compact .qxm stores centres and axes as float32, and its halves' tips
/// lie about 1e-6 of their length apart, where 1e-9 paired 2 of 4lfq's 1,134) and whose axes run
/// opposite ways, each paired once. The union meshes each pair as one tube.
std::vector<std::size_t> bond_halves(const std::vector<Glyph>& glyphs);

/// Meshes every primitive of the model. \throws InvalidInput for an empty model.
ToMeshResult mesh_model(const Model& model, const ToMeshOptions& options = {});

/// Mesh → drawn surface for any triangle mesh, as mesh_model measures its own: at every vertex,
/// edge midpoint and face centroid, the nearest surface the CPU reference draws along the
/// sample's normal line (both ways, within reach); where that is beyond the bound, also along
/// the 13 lines towards the sample's grid neighbours. Every hit is a point of the surface, so
/// each figure is an upper bound of the Euclidean distance. \throws InvalidInput for an empty model.
MeshDistance mesh_distance(const Model& model, const PolygonMesh& mesh, double reach, double bound);

/// The edgewise subdivision of the tetrahedron (0,0,0), (k,0,0), (k,k,0), (k,k,k) into k³
/// tetrahedra (Kuhn's cube split restricted to it): each as four lattice points (x₁ ≥ x₂ ≥ x₃),
/// barycentric counts (k − x₁, x₁ − x₂, x₂ − x₃, x₃). Its faces carry the regular triangle
/// lattice, so neighbours subdivided alike share their face points.
std::vector<std::array<Eigen::Vector3i, 4>> edgewise_subdivision(int k);

}  // namespace quadrix
