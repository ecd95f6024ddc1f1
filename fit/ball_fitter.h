#pragma once
/// Internal to fit/ (fit/slim_fit.cpp's fitter, not an API): one SLIM ball at a time — its
/// radius search, local quadric, sharp and boundary clips, and surface-side check — with the
/// nested point subsamples and the data's faces it reads. The fitter (fit/slim_fitter.h) chooses
/// among the balls this makes.
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "core/io/io.h"
#include "core/quadric.h"
#include "core/slim.h"
#include "fit/data_surface.h"
#include "fit/point_index.h"
#include "fit/slim_fit.h"

namespace quadrix::fit_detail {

struct Ball {
  std::uint32_t centre = 0;  // point index
  double R = 0;
  Quadric g;                 // local: u = (x − c)/R
  bool is_height = false;
  bool is_bounded = true;    // error ≤ E was reached
  double max_taubin = 0, sum_sq_taubin = 0;  // local units × R = world
  std::size_t count = 0;     // points in the ball
  // Sharp features, open boundaries, a face's prism: the patch keeps the sheet of its centre.
  ClipPlanes clips;
  Eigen::Vector3d sheet = Eigen::Vector3d::Zero(), other = Eigen::Vector3d::Zero();  // cluster normals
  Eigen::Vector3d other2 = Eigen::Vector3d::Zero();  // a third sheet's (a corner of three faces), or zero
  bool settled = false;      // the surface side (BallFitter::settle) was checked
  std::int64_t face = -1;    // a face patch (SlimFitOptions::face_patches): the face's plane
  int surface_lattice = 0;   // settle's surface_ok passed on a lattice this fine (lines per side)
  // A face patch on a triangle clipped to its whole prism whose cross-section reaches no farther
  // than local_surface_factor·E past the triangle: its zero set is the data by construction, so
  // neither its lattice nor its rim needs checking on its own.
  bool on_data = false;
  // A disc patch (SlimFitOptions::cover_point_holes): a point's disc (its tangent plane, bent as
  // the data's surface bends it: DataSurface::bend_tensor), kept through repair.
  bool disc = false;
  // Its crease plane moved across a slit (SlimFitter::crease_slits).
  bool relaxed = false;
  // A point of the ball (local u, normal n) belongs to this patch's sheet.
  bool owns(const Eigen::Vector3d& u, const Eigen::Vector3d& n) const {
    return clips.empty() || (clips.keeps(u) && n.dot(sheet) >= n.dot(other) && (other2.isZero() || n.dot(sheet) >= n.dot(other2)));
  }
};

// Nested random subsamples of the cloud (level k holds n/4^k points), each with its own kd-tree:
// a large ball's fit and check use at most max_fit_points and max_check_points of its points, so
// its radius query can run on the coarsest level that still returns max_check_points, not on
// all n (1M torus points: balls of 10⁵ points, queried ~10 times per candidate).
struct Subsamples {
  struct Level {
    std::vector<Eigen::Vector3d> points;
    std::vector<std::uint32_t> ids;  // into the full cloud
    std::unique_ptr<PointIndex> index;
    double scale = 1;  // full-cloud points per point of this level
  };
  std::vector<Level> levels;  // coarsest first; the full cloud is not among them

  Subsamples(const std::vector<Eigen::Vector3d>& P, std::size_t min_points, std::uint64_t seed);
};

// The faces of the data's mesh, for face patches: which face each face sample lies on, and per
// face the sample at its centroid and its largest centroid–vertex distance.
struct FaceSet {
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  const PolygonMesh* mesh = nullptr;
  std::vector<std::uint32_t> face_of;   // per point: its face, or kNone (a cloud point)
  std::vector<std::uint32_t> centroid;  // per face: the point at its centroid, or kNone
  std::vector<double> reach;            // per face: largest centroid–vertex distance
  // A side wall of a face's prism: the plane through one of its edges, perpendicular to the face.
  struct Side {
    Eigen::Vector3d inward;  // unit, in the face's plane, towards the centroid
    double offset = 0;       // the edge's distance from the centroid along -inward
    double length = 0;       // the edge's length
    bool open = false;       // the edge is used by this face only (the data's boundary)
  };
  std::vector<std::vector<Side>> sides;  // per face: one per edge for a convex face of at most
                                         // ClipPlanes::kMax edges, else its longest open edge

  FaceSet(const PolygonMesh& m, std::vector<std::uint32_t> of, const std::vector<Eigen::Vector3d>& P, bool prisms);
  /// Distance from x to face f.
  double distance(std::uint32_t f, const Eigen::Vector3d& x) const;
};

/// Fits one ball: the largest radius around a centre point whose local quadric keeps its points
/// within E and its surface near the data (its own sheet, clipped at sharp features and open
/// boundaries), or a face patch where E is below the data's sampling. Stateless between calls:
/// each thread brings its Scratch.
struct BallFitter {
  const std::vector<Eigen::Vector3d>& P;
  const std::vector<Eigen::Vector3d>& N;
  const PointIndex& index;
  const SlimFitOptions& opt;
  double E;       // world
  double probe;   // world
  const Subsamples* subsamples = nullptr;
  const DataSurface* data = nullptr;  // the points' local surface (tangent discs)
  const FaceSet* faces = nullptr;     // face patches (SlimFitOptions::face_patches)
  // Per point, or null: a ball centred there whose fit fails tries its centre's sheet, clipped
  // (try_sharp), as with opt.sharp, where nonzero: points beside faces found at creases
  // (SlimFitter::beside_crease).
  const std::vector<std::uint8_t>* sharp_at = nullptr;
  double diagonal = 0;
  /// surface_ok on verification's lattice (fine in world units, as SlimFitter::verify_surface
  /// checks each patch alone) where that is finer than its own: set for the repairs' candidates.
  bool verify_lattice = false;
  /// The lattice surface_ok checks a ball of radius R on: lines per side, refinement levels.
  std::pair<int, int> surface_lattice(double R) const;

  struct Scratch {
    std::vector<Neighbour> nb;
    std::vector<Eigen::Vector3d> u, n, fu, fn;
    std::vector<double> fw, fe;
  };

  /// The largest ball around point ci (up to limit) that fits; guess: a nearby ball's radius.
  Ball grow(std::uint32_t ci, Scratch& s, double limit = std::numeric_limits<double>::infinity(), double guess = 0) const;
  /// The ball of radius R around point ci if its fit holds (accept_any: its best fit regardless).
  std::optional<Ball> try_ball(std::uint32_t ci, double R, Scratch& s, bool accept_any = false) const;
  /// Face f's plane clipped to its prism, around its centroid.
  std::optional<Ball> face_patch(std::uint32_t f) const;
  /// The face patch of the face point ci lies on, where E is below the data's sampling.
  std::optional<Ball> face_ball(std::uint32_t ci, Scratch& s) const;
  /// The surface side of a ball: its zero set within the surface bound of the data.
  Ball settle(Ball b, Scratch& s) const;
  bool surface_ok(const Ball& b) const;

private:
  std::optional<Ball> try_both_sides(std::uint32_t ci, double R, Scratch& s) const;
  std::optional<Ball> try_boundary(const Ball& b, const Scratch& s) const;
  std::size_t ball_points(const Eigen::Vector3d& c, double R, Scratch& s) const;
  /// planar: only where each sheet's points lie within E of its plane (the planes between the
  /// sheets are those of flat faces; sharp_at's balls).
  std::optional<Ball> try_sharp(std::uint32_t ci, double R, Scratch& s, bool planar = false) const;
};

}  // namespace quadrix::fit_detail
