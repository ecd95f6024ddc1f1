#include "fit/slim_fitter.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <optional>
#include <tuple>

#include <Eigen/Eigenvalues>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "core/io/io.h"
#include "core/log.h"
#include "core/morton.h"
#include "core/ray.h"
#include "fit/evaluate.h"
#include "fit/surface_error.h"

// The fitter's checks (fit/slim_fitter.h): the points and the drawn surface against their bounds,
// the data's faces outside every ball or seen through from some view, and what fills those.

namespace quadrix::fit_detail {

// Spots found by parallel loops come in the threads' order: sorted by point (or face) and then
// by position, so that the fit does not depend on the scheduling (a torus fitted twice gave 324
// patches one time and 325 the next, where two threads found spots of the same point).
bool by_point_then_spot(const std::pair<std::uint32_t, Eigen::Vector3d>& x, const std::pair<std::uint32_t, Eigen::Vector3d>& y) {
  return std::tie(x.first, x.second.x(), x.second.y(), x.second.z()) < std::tie(y.first, y.second.x(), y.second.y(), y.second.z());
}

// The chosen balls that may hold a point of the triangle abc, nearest centres first.
void SlimFitter::balls_near_triangle(const PointIndex& index, double max_radius, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                         const Eigen::Vector3d& c, std::vector<Neighbour>& nb, std::vector<std::uint32_t>& near) const {
  const auto& slims = result_.model.slims;
  const Eigen::Vector3d mid = (a + b + c) / 3.0;
  const double spread = std::max({(a - mid).norm(), (b - mid).norm(), (c - mid).norm()});
  index.radius(mid, max_radius + spread, nb);
  std::sort(nb.begin(), nb.end(), [](const Neighbour& x, const Neighbour& y) { return x.second < y.second; });
  near.clear();
  for (const auto& [i, d2] : nb)
    if (std::sqrt(d2) < slims[i].radius + spread) near.push_back(std::uint32_t(i));
}

bool SlimFitter::holds(std::uint32_t k, const Eigen::Vector3d& x, double band, const Eigen::Vector3d* n) const {
  const SlimPatch& sp = result_.model.slims[k];
  if (!((x - sp.centre).squaredNorm() < sp.radius * sp.radius)) return false;
  const Eigen::Vector3d u = (x - sp.centre) / sp.radius;
  if (!sp.clips.keeps(u)) return false;
  const Eigen::Vector3d grad = sp.local.gradient(u);
  const double g = sp.local.eval(u), gn = grad.norm();
  if (n && !(std::abs(grad.dot(*n)) >= kHoldSteepestCos * gn)) return false;
  return std::abs(g) * sp.radius <= band * gn;
}

// (Ball and planes are convex, and so is the band about a plane, so a piece whose corners one
// patch holds is held whole, up to a quadric's bending over the piece.)
template <class Emit>
void SlimFitter::uncovered(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& s,
                           const std::vector<std::uint32_t>& near, double band, int depth, int max_depth, Emit&& emit,
                           const Eigen::Vector3d* n, std::size_t* budget) const {
  if (budget && (*budget)-- == 0) {
    *budget = 0;
    return;
  }
  for (const std::uint32_t i : near)
    if (holds(i, p, band, n) && holds(i, q, band, n) && holds(i, s, band, n)) return;
  if (depth == max_depth) {
    for (const Eigen::Vector3d& x : {Eigen::Vector3d((p + q + s) / 3.0), p, q, s})
      if (std::none_of(near.begin(), near.end(), [&](std::uint32_t i) { return holds(i, x, band, n); })) {
        emit(x);
        return;
      }
    return;
  }
  split_in_four(p, q, s, [&](const auto&... piece) { uncovered(piece..., near, band, depth + 1, max_depth, emit, n, budget); });
}

std::array<Eigen::Vector3d, 6> SlimFitter::tangent_ring(std::size_t i, double rho) const {
  const Eigen::Vector3d u = N_[i].unitOrthogonal(), v = N_[i].cross(u);
  std::array<Eigen::Vector3d, 6> ring;
  for (int k = 0; k < 6; ++k) {
    // On the point's disc, bent as the data's surface bends it (DataSurface::bend_height).
    const Eigen::Vector3d t = rho * (std::cos(std::numbers::pi * k / 3.0) * u + std::sin(std::numbers::pi * k / 3.0) * v);
    ring[k] = P_[i] + t + (data_ ? data_->bend_height(i, t) : 0.0) * N_[i];
  }
  return ring;
}

bool SlimFitter::held_whole(const Eigen::Vector3d& p, const std::array<Eigen::Vector3d, 6>& ring, double rho, double band,
                            const PointIndex& centres, double max_radius, std::optional<std::uint32_t>& last,
                            std::vector<Neighbour>& nb, std::vector<std::uint32_t>& near) const {
  const auto whole = [&](std::uint32_t k) {
    return holds(k, p, band) && std::all_of(ring.begin(), ring.end(), [&](const auto& x) { return holds(k, x, band); });
  };
  if (last && whole(*last)) return true;
  // The patches near the ring, nearest centres first: usually the first holds it whole.
  const auto& slims = result_.model.slims;
  centres.radius(p, max_radius + rho, nb);
  std::sort(nb.begin(), nb.end(), [](const Neighbour& x, const Neighbour& y) { return x.second < y.second; });
  near.clear();
  for (const auto& [k, d2] : nb)
    if (std::sqrt(d2) < slims[k].radius + rho) near.push_back(std::uint32_t(k));
  const auto it = std::find_if(near.begin(), near.end(), whole);
  if (it == near.end()) return false;
  last = *it;
  return true;
}

// Spots of the data's faces outside every chosen ball: holes of the drawn surface between
// points that are all covered. A fan triangle some one ball holds whole (its three corners:
// balls are convex) is covered; else it is split in four, down to face_hole_depth levels, and
// a smallest piece contributes its first corner or centroid that no ball holds.
// index: the round's index of the patches' centres; changed: the balls that left or joined
// the model since the last check (none: the first), so a face covered then and far from all
// of them is covered still.
std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> SlimFitter::face_holes(const PointIndex& index, const Changed* changed,
                                                                  bool steep) {
  const auto& slims = result_.model.slims;
  if (!faces_ || slims.empty()) return {};
  double max_radius = 0;
  for (const auto& s : slims) max_radius = std::max(max_radius, s.radius);
  const PolygonMesh& m = *faces_->mesh;
  // A ray along the face's normal meets such a zero set within this of the face (twice the
  // surface bound: the points of a noisy face may lie beyond the bound from a patch within E of
  // its vertices; a face patch across a crease lies hundreds of E away).
  const double band = 2.0 * opt_.surface_factor * E_;
  if (!changed) face_covered_.assign(m.face_count(), 0), steep_spots_.assign(m.face_count(), {});
  // The crease spots only where view_holes will ask about them.
  steep = steep && opt_.view_hole_rays > 0 && face_prisms();
  face_patched_.resize(m.face_count(), 0);
  tbb::enumerable_thread_specific<std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>> found;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m.face_count(), 256), [&](const tbb::blocked_range<std::size_t>& r) {
    auto& out = found.local();
    std::vector<Neighbour> nb;
    std::vector<std::uint32_t> near;
    for (std::size_t f = r.begin(); f != r.end(); ++f) {
      if (faces_->centroid[f] == FaceSet::kNone) continue;  // a sliver: no surface of its own
      const auto vs = m.face(f);
      if (face_covered_[f] && changed) {
        const Eigen::Vector3d& o = P_[faces_->centroid[f]];
        if (!changed->near_ball(o, faces_->reach[f], nb)) continue;
      }
      const std::size_t spots_before = out.size();
      steep_spots_[f].clear();
      for (std::size_t k = 1; k + 1 < vs.size(); ++k) {
        const Eigen::Vector3d &a = m.vertices[vs[0]], &b = m.vertices[vs[k]], &c = m.vertices[vs[k + 1]];
        balls_near_triangle(index, max_radius, a, b, c, nb, near);
        // Inside the ball and its clip planes, its zero set passing within `band` (holds):
        // a boundary plane that stops a sheet short of a crease leaves the strip beyond it
        // uncovered although the ball reaches across, and the prism of a face patch across
        // the crease holds the strip but its plane is elsewhere.
        uncovered(a, b, c, near, band, 0, opt_.face_hole_depth, [&](const Eigen::Vector3d& x) { out.push_back({std::uint32_t(f), x}); });
        // Held, but beside a crease perhaps only by the other face's sheet: for view_holes to
        // ask (while the face is covered and has no face patch). The strip along the edge may
        // be narrower than a piece at face_hole_depth: pieces down to edges of 2E (at most 8
        // levels; only pieces no one patch holds whole are split, at most kSteepPieces of them),
        // at most kSteepSpots a triangle.
        if (!steep || out.size() != spots_before || face_patched_[f]) continue;
        const Eigen::Vector3d cross = (b - a).cross(c - a);
        const double longest2 = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
        if (is_sliver(cross.norm(), longest2)) continue;
        const Eigen::Vector3d n = cross.normalized();
        const double halvings = std::clamp(0.5 * std::log2(longest2 / (4.0 * E_ * E_)), 0.0, 8.0);
        const int depth = std::max(opt_.face_hole_depth, int(std::ceil(halvings)));
        std::size_t kept = 0, budget = kSteepPieces;
        uncovered(a, b, c, near, band, 0, depth, [&](const Eigen::Vector3d& x) {
            if (kept++ < kSteepSpots) steep_spots_[f].push_back({std::uint32_t(k), x});
          }, &n, &budget);
      }
      face_covered_[f] = out.size() == spots_before;
    }
  });
  std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> all;
  for (auto& v : found) all.insert(all.end(), v.begin(), v.end());
  // The same spot from two pieces (a shared corner) once.
  std::sort(all.begin(), all.end(), [](const auto& x, const auto& y) {
    return std::tie(x.first, x.second.x(), x.second.y(), x.second.z()) < std::tie(y.first, y.second.x(), y.second.y(), y.second.z());
  });
  all.erase(std::unique(all.begin(), all.end(), [](const auto& x, const auto& y) { return x.first == y.first && x.second == y.second; }),
            all.end());
  return all;
}

// Holes between the points of a cloud without faces (SlimFitOptions::cover_point_holes): each
// point's coverage disc, a hexagon in its tangent plane point_hole_factor × its spacing wide,
// checked as six fan triangles the way face_holes checks a face. A corner is pulled back to the
// point unless one of its 12 nearest points on its sheet (normals within 60°) lies within 60°
// of its direction and another one's tangent disc holds it within the band: past an open
// boundary, or across a crease (where an estimated normal tilts), the plane leaves the data.
// At most one spot per point; points held at the last check and far from every changed ball
// are held still.
std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> SlimFitter::point_holes(const PointIndex& index, const Changed* changed) {
  const auto& slims = result_.model.slims;
  if (surface_ || !data_ || slims.empty()) return {};
  double max_radius = 0;
  for (const auto& s : slims) max_radius = std::max(max_radius, s.radius);
  const double band = 2.0 * opt_.surface_factor * E_;
  const std::size_t n = P_.size();
  if (!changed) point_covered_.assign(n, 0);
  // Visited in Morton order, each thread asking the patch that last held a disc first: on 1M
  // points nearly every disc lies whole in that one ball.
  if (point_order_.size() != n) point_order_ = morton_order(P_);
  corner_mask_.resize(n, 0);
  corner_known_.resize(n, 0);
  // Which corners stay (computed for the points whose full hexagon no one patch holds).
  const auto mask_of = [&](std::size_t i, double rho, std::vector<Neighbour>& nb) {
    const Eigen::Vector3d u = N_[i].unitOrthogonal(), v = N_[i].cross(u);
    index_->nearest(P_[i], 13, nb);
    std::uint8_t towards = 0, supported = 0;
    for (int k = 0; k < 6; ++k) {
      const Eigen::Vector3d t = std::cos(std::numbers::pi * k / 3.0) * u + std::sin(std::numbers::pi * k / 3.0) * v;
      // On the point's disc, bent as the data's surface bends it (tangent_ring).
      const Eigen::Vector3d x = P_[i] + rho * t + data_->bend_height(i, rho * t) * N_[i];
      for (const auto& [j, d2] : nb) {
        if (j == i || N_[j].dot(N_[i]) < 0.5) continue;
        const Eigen::Vector3d w = P_[j] - P_[i];
        if (w.dot(t) >= 0.5 * (w - w.dot(N_[i]) * N_[i]).norm()) towards |= std::uint8_t(1u << k);
        // Another point's (bent) tangent disc holds the corner (within the band): the plane is
        // the data there, not a tilted normal's plane across a crease. (Flat, the test failed
        // on every corner of an exact sphere's points at 1e-6, whose discs sag 1,000E at that
        // reach: each coverage disc shrank to its point and no hole was found between them.)
        const Eigen::Vector3d y = x - P_[j];
        const Eigen::Vector3d yt = y - y.dot(N_[j]) * N_[j];
        if (std::abs(y.dot(N_[j]) - data_->bend_height(j, yt)) <= band && yt.norm() <= data_->disc_radius(j))
          supported |= std::uint8_t(1u << k);
      }
    }
    return std::uint8_t(towards & supported);
  };
  tbb::enumerable_thread_specific<std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>> found;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    auto& out = found.local();
    std::vector<Neighbour> nb;
    std::vector<std::uint32_t> near;
    std::optional<std::uint32_t> last;  // the patch that last held a whole disc
    std::array<Eigen::Vector3d, 6> corner;
    for (std::size_t o = r.begin(); o != r.end(); ++o) {
      const std::size_t i = point_order_[o];
      const double rho = coverage_radius(i);
      if (!(rho > 0)) continue;
      if (point_covered_[i] && changed && !changed->near_ball(P_[i], rho, nb)) continue;
      const Eigen::Vector3d& p = P_[i];
      corner = tangent_ring(i, rho);
      if (held_whole(p, corner, rho, band, index, max_radius, last, nb, near)) {
        point_covered_[i] = 1;
        continue;
      }
      if (!corner_known_[i]) corner_mask_[i] = mask_of(i, rho, nb), corner_known_[i] = 1;
      for (int k = 0; k < 6; ++k)
        if (!(corner_mask_[i] >> k & 1u)) corner[k] = p;
      bool spot = false;
      for (int k = 0; k < 6 && !spot; ++k)
        uncovered(p, corner[k], corner[(k + 1) % 6], near, band, 0, opt_.point_hole_depth, [&](const Eigen::Vector3d& x) {
          if (!spot) out.push_back({std::uint32_t(i), x});
          spot = true;
        });
      point_covered_[i] = !spot;
    }
  });
  std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> all;
  for (auto& v : found) all.insert(all.end(), v.begin(), v.end());
  std::sort(all.begin(), all.end(), by_point_then_spot);
  return all;
}

// The candidate ball centred on each point with a hole (the radius search and surface side as
// for any candidate), largest first, kept through pruning when it reaches its spot (within 0.9
// of its radius, where its weight is not negligible) and its centre is not within half the
// radius of one taken here; the others join `far` (for disc patches).
std::size_t SlimFitter::add_point_balls(const std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& spots,
                                        std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& far) {
  std::vector<std::uint32_t> centres;
  std::vector<double> caps;
  for (const auto& [i, x] : spots) centres.push_back(i), caps.push_back(cap_[i]);
  const std::vector<std::uint32_t> fresh = new_candidates(centres, caps);
  std::vector<std::size_t> order(fresh.size());
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::sort(order.begin(), order.end(), [&](auto a, auto b) { return balls_[fresh[a]].R > balls_[fresh[b]].R; });
  std::vector<std::uint32_t> taken;
  for (const auto k : order) {
    const std::uint32_t b = fresh[k];
    if (near_taken(b, taken)) continue;
    if (!balls_[b].is_bounded || !((spots[k].second - P_[balls_[b].centre]).norm() < 0.9 * balls_[b].R)) {
      far.push_back(spots[k]);
      continue;
    }
    take_pinned(b, taken);
  }
  return taken.size();
}

// Each point's disc patch, kept through pruning: its tangent plane in a ball of
// disc_patch_reach × its coverage disc. (The height quadric of its 12 nearest points bent with
// the true surface a little better — 5,000 points drawn from the bunny at 1e-3: 7.7 % of the
// pixels beyond 2E of the mesh instead of 10.5 % — but ran off the points' tangent discs: 1 % of
// the pixels beyond 2E of them instead of 0.001 %.)
std::size_t SlimFitter::add_disc_patches(const std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& spots, bool on_data) {
  const std::size_t first = balls_.size();
  const double bound = opt_.surface_factor * E_;
  std::vector<Neighbour> nb;
  std::vector<std::uint32_t> donors;  // points whose disc this call already added for another spot
  for (const auto& [hole_point, x] : spots) {
    // The disc of point i reaching its spot well inside (a hole between the points lies up to a
    // spacing away), as the data's surface bends it (DataSurface::bend_tensor): its tangent
    // plane where the disc is flat.
    const auto disc_radius = [&](std::size_t i) { return std::max(disc_patch_radius(i), 1.25 * (x - P_[i]).norm()); };
    const auto on_disc = [&](std::size_t i, const Eigen::Matrix3d& K, const Eigen::Vector3d& t) {
      return Eigen::Vector3d(P_[i] + t + 0.5 * t.dot(K * t) * N_[i]);
    };
    // The patch at the spot and on two rings (half and all of the ball) within the bound.
    const auto stays_on_data = [&](std::size_t i) {
      const double R = disc_radius(i);
      const Eigen::Matrix3d K = data_->bend_tensor(i);
      const Eigen::Vector3d u = N_[i].unitOrthogonal(), v = N_[i].cross(u);
      const Eigen::Vector3d xt = x - P_[i] - N_[i].dot(x - P_[i]) * N_[i];
      if (!(data_->distance(on_disc(i, K, xt), 2.0 * bound) <= bound)) return false;
      for (int k = 0; k < 12; ++k) {
        const Eigen::Vector3d t = std::cos(std::numbers::pi * k / 6.0) * u + std::sin(std::numbers::pi * k / 6.0) * v;
        if (!(data_->distance(on_disc(i, K, (k % 2 ? 0.5 : 0.98) * R * t), 2.0 * bound) <= bound)) return false;
      }
      return true;
    };
    std::size_t i = hole_point;
    if (on_data && !stays_on_data(i)) {
      // Where the point's own disc runs off (a sparse, curved stretch of a scan: bun000 at 1e-3
      // kept 5 holes so), the disc of another of the spot's nearest points on the same sheet
      // may stay on the data and cover it.
      constexpr std::size_t kDiscDonors = 8;
      index_->nearest(x, kDiscDonors + 1, nb);
      bool found = false;
      for (const auto& [j, d2] : nb) {
        if (j == hole_point || N_[j].dot(N_[hole_point]) < 0.5 || std::find(donors.begin(), donors.end(), j) != donors.end() ||
            !stays_on_data(j))
          continue;
        i = j;
        found = true;
        donors.push_back(j);
        break;
      }
      // Either way the point is not tried again: counted if its hole stays.
      disc_shrunk_[hole_point] = 1;  // as a disc patch that ran off
      if (!found) continue;
    }
    const double R = disc_radius(i);
    if (!(R > 0)) continue;
    const Eigen::Matrix3d K = data_->bend_tensor(i);
    // In the ball's local units u = (x − p)/R: n·u − ½R·uᵀKu = 0 (a plane where K = 0).
    Quadric disc = Quadric::plane(N_[i], 0.0);
    disc.A = -0.5 * R * K;  // g = uᵀAu + 2bᵀu with b = n/2
    Ball b{i, R, disc, true, true, 0, 0, 0, ClipPlanes{}};
    b.count = 1;
    b.settled = true;
    b.disc = true;
    // Not on_data: a plane a spacing wide leaves a curved tip (the bunny's ears from 5,000
    // points: 20E off).
    balls_.push_back(std::move(b));
    grow_candidate_arrays();
    covers_.back() = {i};
  }
  for (std::size_t b = first; b < balls_.size(); ++b) {
    pinned_[b] = 1;
    take(std::uint32_t(b));
  }
  return balls_.size() - first;
}

// The view of a spot near point i: along its normal, from outside its disc (its radius and 4E
// out), or from halfway to the data's next crossing where one faces it nearer (a paw against a
// body, a slit's far lip): the view starts outside.
// The spot's own sheet is passed first: its crossings seen from behind (normals along n), which
// lie farther than the bound above a spot where the data bends between the points more than its
// discs follow (800 points of an exact sphere at 1e-6: ring spots one spacing out lay 60E below
// their neighbours' discs, the view started 2E above those, its rays beside it inside the
// sphere, and no hole counted while 99.9 % of bench fit's pixels were open).
Ray SlimFitter::spot_ray(std::size_t i, const Eigen::Vector3d& x) const {
  const Eigen::Vector3d& n = N_[i];
  double own = 2.0 * opt_.surface_factor * E_;  // past the spot's own sheet
  double L = data_->disc_radius(i) + 4.0 * E_;
  for (int k = 0; k < 8; ++k) {
    const auto h = data_->first_hit(Ray{x, n}, own, L);
    if (!h) break;
    if (h->normal.dot(n) > 0.5) {  // the own sheet, from behind
      own = h->t + 2.0 * opt_.surface_factor * E_;
      L = std::max(L, own + 4.0 * E_);
      continue;
    }
    L = 0.5 * (own + h->t);
    break;
  }
  return Ray{x + L * n, -n};
}

// Where a ray shows a hole the way bench fit counts one (judge_ray): the data there (its point),
// or nothing. As bench fit counts a hole only away from the data's silhouette (a band of the
// bound, or of a cloud's disc radius: discs reach that far past an open boundary, the fit's
// surface rightly not), six rays as far to the side must meet the data's front too.
std::optional<Eigen::Vector3d> SlimFitter::seen_hole(const Ray& ray, const ReferenceScene& scene, const TraceOptions& trace) const {
  const double bound = opt_.surface_factor * E_;
  const auto hit = scene.trace(ray, 0.0, std::numeric_limits<double>::infinity(), trace);
  const RayVerdict v = judge_ray(*data_, ray, hit ? hit->t : -1.0, bound);
  if (!v.counts || !v.hole) return std::nullopt;
  const Eigen::Vector3d x = ray.at(v.data_t);
  if (!data_around(x, ray.dir, v.data_t, std::max(bound, v.reach))) return std::nullopt;
  return x;
}

// The points' holes a view sees: of their coverage holes (spots), those seen_point_holes sees,
// and those between the points, one spot per point, by point.
std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> SlimFitter::seen_holes(
    const std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& spots, const PointIndex& centres,
    const ReferenceScene& scene) const {
  auto out = seen_point_holes(spots, scene);
  const auto by_point = [](const auto& x, const auto& y) { return x.first < y.first; };
  std::sort(out.begin(), out.end(), by_point);
  const std::size_t seen = out.size();
  for (const auto& h : holes_between_points(centres, scene))
    if (!std::binary_search(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(seen), h, by_point)) out.push_back(h);
  // Holes between the points are filed under the point nearest each: one spot per point.
  std::stable_sort(out.begin(), out.end(), by_point);
  out.erase(std::unique(out.begin(), out.end(), [](const auto& x, const auto& y) { return x.first == y.first; }), out.end());
  return out;
}

// Holes between the points that no coverage disc reaches (a disc reaches 0.6 of the spacing: on
// the sparse half of the uneven sphere at 1e-3 two holes 20E across lay between points with
// every disc held, 30 of 33,779 pixels at 160²). Around each point, six spots one spacing out in
// its tangent plane; where no one patch holds them all, each spot no patch holds is seen along
// the point's normal, as seen_point_holes sees a coverage spot. A spot past an open boundary, or
// off a curved sheet, finds no data there to count (judge_ray), so only the view decides.
std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> SlimFitter::holes_between_points(const PointIndex& centres,
                                                                                      const ReferenceScene& scene) const {
  const auto& slims = result_.model.slims;
  if (!data_ || slims.empty()) return {};
  double max_radius = 0;
  for (const auto& sp : slims) max_radius = std::max(max_radius, sp.radius);
  TraceOptions trace;
  trace.slim = blend();
  const double band = 2.0 * opt_.surface_factor * E_;  // as point_holes holds a coverage disc
  if (point_order_.size() != P_.size()) return {};
  tbb::enumerable_thread_specific<std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>> found;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P_.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    auto& out = found.local();
    std::vector<Neighbour> nb;
    std::vector<std::uint32_t> near;
    std::optional<std::uint32_t> last;  // the patch that last held a whole ring
    std::array<Eigen::Vector3d, 6> spot;
    for (std::size_t o = r.begin(); o != r.end(); ++o) {
      const std::size_t i = point_order_[o];
      const double rho = data_->spacing(i);
      if (!(rho > 0)) continue;
      const Eigen::Vector3d& p = P_[i];
      spot = tangent_ring(i, rho);
      if (held_whole(p, spot, rho, band, centres, max_radius, last, nb, near)) continue;
      for (const auto& x : spot) {
        if (std::any_of(near.begin(), near.end(), [&](std::uint32_t k) { return holds(k, x, band); })) continue;
        if (const auto y = seen_hole(spot_ray(i, x), scene, trace)) {
          // Filled from the point nearest the hole (its ball reaches it soonest).
          index_->nearest(*y, 1, nb);
          out.push_back({nb.empty() ? std::uint32_t(i) : std::uint32_t(nb[0].first), *y});
          break;
        }
      }
    }
  });
  std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> all;
  for (auto& f : found) all.insert(all.end(), f.begin(), f.end());
  std::sort(all.begin(), all.end(), by_point_then_spot);
  return all;
}

std::uint8_t SlimFitter::beside_crease(std::size_t i, std::vector<Neighbour>& nb) const {
  if (surface_ || !data_ || !index_) return 0;
  const DataSurfaceOptions defaults;
  index_->nearest(P_[i], defaults.crease_neighbours + 1, nb);
  // Two faces' points: their faces' planes turned as a crease's (the planes spread across whole
  // faces, so one face's points alone are any flat face's).
  const Eigen::Vector3d* first = nullptr;
  for (const auto& [j, d2] : nb) {
    if (!on_face(j)) continue;
    const Eigen::Vector3d& n = data_->normal(j);
    if (!first) first = &n;
    else if (first->dot(n) < defaults.crease_cos) return kOnFace | kAtEdge;
  }
  return first ? kOnFace : 0;
}

// A point's coverage hole is seen when the view along the point's normal, through the spot, from
// outside its disc, shows a hole the way bench fit counts them (judge_ray: the data's tangent discs
// there, sure enough to count, and the blend showing nothing, or something nearer the data's far
// side than its front). The coverage test alone also flags discs tilted off a crease or a corner,
// whose fills stood 5–13E past a box's corners; this asks what a viewer sees.
std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> SlimFitter::seen_point_holes(
    const std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& spots, const ReferenceScene& scene) const {
  if (!data_) return {};
  TraceOptions trace;
  trace.slim = blend();
  std::vector<std::uint8_t> seen(spots.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, spots.size(), 16), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t k = r.begin(); k != r.end(); ++k) {
      const auto& [i, x] = spots[k];
      seen[k] = seen_hole(spot_ray(i, x), scene, trace).has_value();
    }
  });
  std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> out;
  for (std::size_t k = 0; k < spots.size(); ++k)
    if (seen[k]) out.push_back(spots[k]);
  return out;
}

// Two sheets' patches at a crease are each clipped at their own estimate of it (try_sharp:
// where the two tangent planes are equally far), and where the two planes part they leave a
// slit between the points that neither keeps: the kitten at 1e-3 showed the far side through
// one along its mouth, 8E wide, between its points (no coverage disc reached it). Filling it
// with new patches stood out as fins at corners (see verify_and_repair); the patch whose own
// zero set runs across the slit keeps it instead. (Moving planes onto the coverage discs' spots
// that a clipped zero set passes within E of was tried first: on clouds drawn from the bunny and
// the armadillo, 50–140 patches moved, mostly where a smooth surface's spot lies off the data,
// and their sheets ran up to 3.5E off the points' discs.)
std::vector<std::pair<std::size_t, ClipPlanes>> SlimFitter::crease_slits(const PointIndex& centres, const ReferenceScene& scene,
                                                                         const std::vector<std::uint8_t>& at_fault,
                                                                         std::size_t& open) const {
  open = 0;
  TraceOptions trace;
  trace.slim = blend();
  const auto& slims = result_.model.slims;
  double max_radius = 0;
  for (const auto& sp : slims) max_radius = std::max(max_radius, sp.radius);
  std::vector<std::pair<std::size_t, ClipPlanes>> out;
  std::vector<Neighbour> nb;
  // The cut edges of the patches clipped at a crease (try_sharp), on a lattice of lines in each
  // plane: where no other patch holds an edge point, the patch's own sheet is followed across its
  // plane (steps of E/2, back onto its zero set each time, up to half its radius) to where
  // another patch holds it; its plane moves there, E/2 past. None found: an edge with nothing
  // beyond (left as it is).
  // Held: another patch's zero set within E of the point (the sheet followed meets it there).
  const double band = E_;
  const auto held_by_other = [&](std::size_t self, const Eigen::Vector3d& x) {
    centres.radius(x, max_radius, nb);
    for (const auto& [k, d2] : nb)
      if (k != self && holds(std::uint32_t(k), x, band)) return true;
    return false;
  };
  // The points where a patch's zero set meets the plane c (local units), on 8 lines along each of
  // two directions in the plane, inside 0.9 of the ball.
  const auto edge_points = [](const SlimPatch& sp, const ClipPlane& c, auto&& visit) {
    const double half2 = 0.81 - c.d * c.d;
    if (!(half2 > 0)) return;
    const double half = std::sqrt(half2);
    const Eigen::Vector3d o = -c.d * c.n, e1 = c.n.unitOrthogonal(), e2 = c.n.cross(e1);
    for (int family = 0; family < 2; ++family) {
      const Eigen::Vector3d f = family == 0 ? e1 : e2, across = family == 0 ? e2 : e1;
      for (int j = 0; j < 8; ++j) {
        const Ray line{o + half * (-1.0 + (2.0 * j + 1.0) / 8.0) * across, f};
        const Roots roots = solve_ray_quadratic(ray_quadratic(sp.local, line));  // core's solver
        for (int r = 0; r < roots.count; ++r)
          if (const Eigen::Vector3d u = line.at(roots.t[r]); u.squaredNorm() < 0.81) visit(u);
      }
    }
  };
  for (std::size_t k = 0; k < slims.size(); ++k) {
    const Ball& ball = balls_[chosen_[k]];
    const SlimPatch& sp = slims[k];
    // Crease patches only: try_sharp's two sheets within 120° (not the two sides of a thin part,
    // which try_both_sides splits the same way), and not a patch the repair is about to replace.
    if (ball.other.isZero() || sp.clips.size() != 1 || ball.sheet.dot(ball.other) < -0.5) continue;
    if (k < at_fault.size() && at_fault[k]) continue;
    const ClipPlane& c = *sp.clips.begin();
    const double step = 0.5 * E_ / sp.radius;
    double needed = 0;
    edge_points(sp, c, [&](const Eigen::Vector3d& u) {
      if (held_by_other(k, sp.centre + sp.radius * u)) return;
      // A hole only where the blend shows nothing within 2E of the spot just past the edge, seen
      // along the sheet's normal from outside (a smooth surface's clipped patches are mostly
      // overlapped by others that the point test misses: relaxing them all ran sheets 3.5E off
      // the points' discs; the whole ray would see the far side of a groove through its slit).
      {
        const Eigen::Vector3d g = sp.local.gradient(u).normalized();
        const Eigen::Vector3d w = (-c.n + c.n.dot(g) * g).normalized();
        const Eigen::Vector3d x = sp.centre + sp.radius * (u + step * w);
        const double L = 4.0 * E_;
        if (!w.allFinite() || scene.trace(Ray{x + L * g, -g}, 0.0, L + 2.0 * E_, trace)) return;
        // ... and only where that view meets the data: past a convex crease's edge it passes the
        // solid by, and the sheet clipped at the crease is whole (with the discs cut at creases,
        // a plate 1 × 1 × 0.04 at 3e-3 counted 36 such "slits", a hole share of 1.8e-3, where the
        // views against the true box see 1 hole pixel of 126,352 either way; now none).
        if (!data_->first_hit(Ray{x + L * g, -g}, 0.0, L + 2.0 * E_)) return;
        // ... and the data's surface goes on past the spot: within 2E of its silhouette in this
        // view (a box's face seen head-on, whose edge is the box's outline) a slit is no hole
        // bench fit counts, and the crease's line, estimated, may lie within E of the edge: a box
        // turned and moved 1e5 from the origin, without normals, at 1e-3, counted 4 and 7 slits
        // in two samplings, 1 and 4 of them such, all within 0.4E of its edges).
        if (!data_->first_hit(Ray{x + 2.0 * E_ * w + L * g, -g}, 0.0, L + 2.0 * E_)) return;
      }
      // Across the plane along the sheet: −n with the gradient's part taken out.
      Eigen::Vector3d y = u;
      for (int m = 1; m <= 64 && m * step <= 0.5; ++m) {  // up to 32E, at most half the radius
        const Eigen::Vector3d gy = sp.local.gradient(y).normalized();
        const Eigen::Vector3d w = -c.n + c.n.dot(gy) * gy;
        if (!(w.norm() > 1e-6)) return;
        y += step * w.normalized();
        const Eigen::Vector3d gz = sp.local.gradient(y);
        if (!(gz.squaredNorm() > 0)) return;
        y -= sp.local.eval(y) / gz.squaredNorm() * gz;
        if (!(y.squaredNorm() < 0.81)) return;
        if (held_by_other(k, sp.centre + sp.radius * y)) {
          ++open;
          needed = std::max(needed, -(c.n.dot(y) + c.d) + step);
          return;
        }
      }
    });
    if (!(needed > 0)) continue;
    // The moved plane's own cut edge must stay on the data wherever no other patch holds it:
    // else the sheet runs on past a rounded crease as a fin (bunny from 50,000 points at 1e-3,
    // moved without this: 1.7× the surface beyond 2E of the mesh).
    // (A plane moved out of the ball's inner 0.9 has no edge left there to check: not moved.)
    const ClipPlane moved_plane{c.n, c.d + needed};
    bool on_data = true;
    std::size_t checked = 0;
    edge_points(sp, moved_plane, [&](const Eigen::Vector3d& u) {
      const Eigen::Vector3d x = sp.centre + sp.radius * u;
      ++checked;
      if (on_data && !held_by_other(k, x) && !(data_->distance(x, 2.0 * E_) <= E_)) on_data = false;
    });
    if (on_data && checked > 0) out.emplace_back(k, ClipPlanes::of(moved_plane));
  }
  return out;
}

void SlimFitter::relax_clips(const std::vector<std::pair<std::size_t, ClipPlanes>>& relaxed) {
  for (const auto& [k, clips] : relaxed) {
    const std::uint32_t b = chosen_[k];
    Ball c = balls_[b];
    c.clips = clips;
    c.relaxed = true;
    // The strip the plane uncovers has not been checked alone: verify_surface samples the zero
    // set's lattice again (settle's lattice is the old planes').
    c.surface_lattice = 0;
    balls_.push_back(std::move(c));
    grow_candidate_arrays();
    const auto nb = std::uint32_t(balls_.size() - 1);
    covers_[nb] = covers_[b];
    pinned_[nb] = 1;
    chosen_flag_[b] = 0;
    chosen_flag_[nb] = 1;
    chosen_[k] = nb;
  }
}

// Holes a view sees although the balls cover the face: a ray through a face's spot from a
// direction within view_hole_angle_deg of its normal that meets no patch near the face (a patch
// leaning against the face at a grazing view, a hit just outside its ball's rim or clip
// planes). The lattice check above is view-independent and cannot see these (buddha at 1e-2:
// hole pixels inside balls whose zero sets pass 0.002–0.15E from the data). Each fan triangle's
// centroid is seen along its normal and along two cones of view_hole_rays directions about it,
// from L before it (L the surface band at the widest angle) on (data_front, the blend,
// data_around). Faces covered at the last check and far from every changed ball are
// skipped; faces that hold a face patch already are not checked (their prism holds the spot).
// Whether the view along d sees the data at x (the first data hit from L before it is x, from
// its front) and the data covers the view's neighbourhood (rays surface_factor·E to each side
// meet it from the front too, so x is not on the data's silhouette): where the model then shows
// nothing anywhere on that ray, it is a hole as bench fit counts them (fit/surface_error.h).
// Data only: the same answer every round.
// Asked in two steps (data_front, then data_around), so that the blend is traced between them:
// where the model shows something on the ray, the six side rays are not needed (armadillo at
// 1e-3: mesh ray casts were 19 % of the fit).
bool SlimFitter::data_front(const Eigen::Vector3d& x, const Eigen::Vector3d& d, double L) const {
  bool front = false;
  const auto t = data_->intersect(Ray{x - L * d, d}, 0.0, &front, L + 1e-3 * E_);  // farther fails anyway
  return t && front && std::abs(*t - L) <= 1e-3 * E_;
}

bool SlimFitter::data_around(const Eigen::Vector3d& x, const Eigen::Vector3d& d, double L, double r) const {
  const Eigen::Vector3d o = x - L * d;
  const Eigen::Vector3d u = d.unitOrthogonal(), v = d.cross(u);
  if (!(r > 0)) r = opt_.surface_factor * E_;
  static const std::array<Eigen::Vector2d, 6> kAround = [] {
    std::array<Eigen::Vector2d, 6> a;
    for (int k = 0; k < 6; ++k) a[k] = {std::cos(std::numbers::pi * k / 3.0), std::sin(std::numbers::pi * k / 3.0)};
    return a;
  }();
  // Each side ray's first hit, asked within 2L first (where it nearly always lies: the walk
  // prunes the far boxes from the start), else anywhere.
  const auto front_first = [&](const Ray& ray) {
    bool f = false;
    if (data_->intersect(ray, 0.0, &f, 2.0 * L)) return f;
    return data_->intersect(ray, 0.0, &f).has_value() && f;
  };
  for (const Eigen::Vector2d& a : kAround)
    if (!front_first(Ray{o + r * (a[0] * u + a[1] * v), d})) return false;
  return true;
}

double patch_bend(const SlimPatch& patch) {
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(patch.local.A, Eigen::EigenvaluesOnly).eigenvalues().cwiseAbs().maxCoeff();
}

// The proofs of meets_views and meets_every_view: fit/slim_fitter.h.
PatchAtSpot patch_at_spot(const SlimPatch& patch, const Eigen::Vector3d& x) {
  PatchAtSpot a;
  a.u = (x - patch.centre) / patch.radius;
  a.r = a.u.norm();
  if (!(a.r < 1.0)) return a;
  a.inside = true;
  a.g = patch.local.gradient(a.u);
  a.g0 = std::abs(patch.local.eval(a.u));
  return a;
}

bool meets_views(const SlimPatch& patch, double bend, const PatchAtSpot& at, double A1, double reach) {
  const double disc = A1 * A1 - 4.0 * bend * at.g0;
  if (!at.inside || !(A1 > 0) || !(disc > 0)) return false;
  const double rho = 2.0 * at.g0 / (A1 + std::sqrt(disc)) * (1.0 + 1e-6) + 1e-9;
  if (!(rho * patch.radius <= reach) || !(at.r + rho < 1.0)) return false;
  for (const ClipPlane& c : patch.clips)
    if (!(c.n.dot(at.u) + c.d > rho * c.n.norm())) return false;
  return true;
}

bool meets_every_view(const SlimPatch& patch, double bend, const PatchAtSpot& at, const Eigen::Vector3d& n, double widest,
                      double reach) {
  if (!at.inside) return false;
  const double gn = at.g.dot(n);
  return meets_views(patch, bend, at, std::cos(widest) * gn - std::sin(widest) * (at.g - gn * n).norm(), reach);
}

bool meets_every_view(const SlimPatch& patch, double bend, const Eigen::Vector3d& x, const Eigen::Vector3d& n, double widest,
                      double reach) {
  return meets_every_view(patch, bend, patch_at_spot(patch, x), n, widest, reach);
}

std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> SlimFitter::view_holes(const ReferenceScene& scene, const PointIndex& index,
                                                                  const Changed* changed) {
  const auto& slims = result_.model.slims;
  if (!faces_ || slims.empty() || opt_.view_hole_rays <= 0) return {};
  double max_radius = 0;
  for (const auto& s : slims) max_radius = std::max(max_radius, s.radius);
  const PolygonMesh& m = *faces_->mesh;
  const double widest = std::clamp(opt_.view_hole_angle_deg, 0.0, 85.0) * std::numbers::pi / 180.0;
  const double L = 2.0 * opt_.surface_factor * E_ / std::cos(widest);
  std::vector<double> bend(slims.size());
  for (std::size_t i = 0; i < slims.size(); ++i) bend[i] = patch_bend(slims[i]);
  if (!changed) view_clear_.assign(m.face_count(), 0), view_data_.assign(m.face_count(), {});
  view_clear_.resize(m.face_count(), 0);
  view_data_.resize(m.face_count());
  face_patched_.resize(m.face_count(), 0);
  TraceOptions trace;
  trace.slim = blend();
  // The view directions in the face's frame (n, t1, t2): j = 0 the normal; then `rays` at half
  // the widest angle, `rays` at it, the outer cone turned by half a step.
  const int rays = opt_.view_hole_rays;
  std::vector<Eigen::Vector3d> cone;
  for (int j = 0; j <= 2 * rays; ++j) {
    const int ring = j == 0 ? 0 : (j - 1) / rays + 1;
    const double theta = widest * ring / 2.0;
    const double phi = 2.0 * std::numbers::pi * ((j - 1) % rays + (ring == 2 ? 0.5 : 0.0)) / rays;
    cone.emplace_back(std::cos(theta), std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi));
  }
  static const std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> no_spots;
  tbb::enumerable_thread_specific<std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>> found;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m.face_count(), 128), [&](const tbb::blocked_range<std::size_t>& r) {
    auto& out = found.local();
    std::vector<Neighbour> nb;
    std::vector<std::uint32_t> near;
    std::vector<PatchAtSpot> at;  // near's patches seen from the spot
    std::vector<std::uint8_t> fresh(cone.size());  // the data's answers for a crease spot's views
    for (std::size_t f = r.begin(); f != r.end(); ++f) {
      if (faces_->centroid[f] == FaceSet::kNone || !face_covered_[f] || face_patched_[f]) continue;
      const Eigen::Vector3d& o = P_[faces_->centroid[f]];
      if (view_clear_[f] && changed && !changed->near_ball(o, faces_->reach[f] + 2.0 * opt_.surface_factor * E_, nb)) continue;
      const auto vs = m.face(f);
      bool clear = true;
      // The data's answers for this face's rays (fan triangle, spot, direction): 0 not asked
      // yet, 1 seen away from a silhouette, 2 not, 3 seen (data_front), the side rays not asked.
      std::vector<std::uint8_t>& seen = view_data_[f];
      const std::size_t spots = std::size_t(1) << (2 * opt_.view_hole_depth);
      seen.resize((std::max<std::size_t>(vs.size(), 2) - 2) * spots * cone.size(), 0);
      for (std::size_t k = 1; k + 1 < vs.size() && clear; ++k) {
        std::size_t spot = (k - 1) * spots;
        const Eigen::Vector3d &a = m.vertices[vs[0]], &b = m.vertices[vs[k]], &c = m.vertices[vs[k + 1]];
        Eigen::Vector3d n = (b - a).cross(c - a);
        if (!(n.norm() > 0)) continue;
        n.normalize();
        if (n.dot(N_[faces_->centroid[f]]) < 0) n = -n;
        const Eigen::Vector3d t1 = (b - a).normalized(), t2 = n.cross(t1);
        // The balls that hold the triangle's spots: one of their patches hit on the ray makes
        // the blend hit it (each patch's own first hit, as the blend's first pass takes it), so
        // only a ray none of them meets is traced through the scene.
        balls_near_triangle(index, max_radius, a, b, c, nb, near);
        // The patch that last met a view is asked first (neighbouring spots share patches).
        const auto met_by = [&](std::size_t k) {
          if (k > 0) std::swap(near[0], near[k]), std::swap(at[0], at[k]);
          return true;
        };
        // A patch that provably meets this one view (meets_views) spares the ray's solve; else
        // the ray is solved against each patch.
        const auto local_hit = [&](const Ray& ray) {
          for (std::size_t k = 0; k < near.size(); ++k)
            if (meets_views(slims[near[k]], bend[near[k]], at[k], -at[k].g.dot(ray.dir), L)) return met_by(k);
          Hit h;
          for (std::size_t k = 0; k < near.size(); ++k)
            if (const std::uint32_t i = near[k];
                intersect_slim_patch(slims[i], ray, 0.0, 2.0 * L, h) && (h.point - slims[i].centre).norm() < slims[i].radius)
              return met_by(k);
          return false;
        };
        // One spot x of the face: asked[j], the data's answer for view j so far (see seen).
        const auto check_spot = [&](const Eigen::Vector3d& x, std::uint8_t* asked) {
          at.resize(near.size());
          for (std::size_t k = 0; k < near.size(); ++k) at[k] = patch_at_spot(slims[near[k]], x);
          // A patch that provably meets every view of the spot spares all its rays.
          for (std::size_t k = 0; k < near.size(); ++k)
            if (meets_every_view(slims[near[k]], bend[near[k]], at[k], n, widest, L)) {
              met_by(k);
              return;
            }
          for (std::size_t j = 0; j < cone.size(); ++j) {
            const Eigen::Vector3d d = -(cone[j][0] * n + cone[j][1] * t1 + cone[j][2] * t2).normalized();
            if (local_hit(Ray{x - L * d, d})) continue;
            if (asked[j] == 0) asked[j] = data_front(x, d, L) ? 3 : 2;
            if (asked[j] == 2) continue;
            // The whole ray through the blend: where it shows something, no hole whatever the
            // side rays would say.
            if (scene.trace(Ray{x - L * d, d}, 0.0, kInf, trace)) continue;
            if (asked[j] == 3) asked[j] = data_around(x, d, L) ? 1 : 2;
            if (asked[j] == 1) {
              out.push_back({std::uint32_t(f), x});
              clear = false;
              return;
            }
          }
        };
        // The spots: the centroids of the face's pieces split in four view_hole_depth times.
        const auto check = [&](const auto& self, const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& s,
                               int depth) -> void {
          if (!clear) return;
          if (depth < opt_.view_hole_depth) {
            split_in_four(p, q, s, [&](const auto&... piece) { self(self, piece..., depth + 1); });
            return;
          }
          check_spot((p + q + s) / 3.0, &seen[spot++ * cone.size()]);
        };
        check(check, a, b, c, 0);
        // Then the spots beside a crease that only a steep sheet holds (face_holes), on this
        // triangle (the data's answers asked afresh: few faces have them).
        for (const auto& [fan, x] : f < steep_spots_.size() ? steep_spots_[f] : no_spots) {
          if (!clear) break;
          if (fan != k) continue;
          std::fill(fresh.begin(), fresh.end(), std::uint8_t(0));
          check_spot(x, fresh.data());
        }
      }
      view_clear_[f] = clear;
    }
  });
  std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> all;
  for (auto& v : found) all.insert(all.end(), v.begin(), v.end());
  std::sort(all.begin(), all.end(), by_point_then_spot);
  return all;
}

bool SlimFitter::near_taken(std::uint32_t b, const std::vector<std::uint32_t>& taken) const {
  const Eigen::Vector3d& c = P_[balls_[b].centre];
  return std::any_of(taken.begin(), taken.end(), [&](auto t) { return (P_[balls_[t].centre] - c).norm() < 0.5 * balls_[t].R; });
}

void SlimFitter::take_pinned(std::uint32_t b, std::vector<std::uint32_t>& taken) {
  cap_[balls_[b].centre] = std::min(cap_[balls_[b].centre], balls_[b].R);
  pinned_[b] = 1;
  take(b);
  taken.push_back(b);
}

// A face patch (BallFitter::face_patch) for each face that holds a spot, kept through pruning.
std::size_t SlimFitter::add_face_patches(const std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& spots) {
  const std::size_t first = balls_.size();
  for (std::size_t k = 0; k < spots.size(); ++k) {
    if (k > 0 && spots[k].first == spots[k - 1].first) continue;  // sorted by face
    if (auto b = fitter_->face_patch(spots[k].first)) {
      balls_.push_back(std::move(*b));
      face_patched_.resize(faces_->mesh->face_count(), 0);
      face_patched_[spots[k].first] = 1;
    }
  }
  grow_candidate_arrays();
  std::vector<Neighbour> nb;
  for (std::size_t b = first; b < balls_.size(); ++b) {
    cover_of(b, nb);
    pinned_[b] = 1;
    take(std::uint32_t(b));
  }
  return balls_.size() - first;
}

// A regular ball (radius search, surface side) at the centroid of each face that holds a spot
// (the centroid is one of the points), largest first, kept through pruning. A face whose
// centroid lies within half the radius of a ball taken here needs none of its own; a face whose
// ball comes out smaller than view_ball_min_reach × the face (or as a face patch, or unbounded)
// joins `small` for a face patch instead. Returns the number of balls taken.
std::size_t SlimFitter::add_view_balls(const std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& spots,
                           std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& small) {
  std::vector<std::uint32_t> centres, face;
  std::vector<double> caps;
  for (std::size_t k = 0; k < spots.size(); ++k) {
    if (k > 0 && spots[k].first == spots[k - 1].first) continue;
    const auto c = faces_->centroid[spots[k].first];
    centres.push_back(c);
    face.push_back(spots[k].first);
    caps.push_back(cap_[c]);
  }
  const std::size_t first = balls_.size();
  std::vector<std::uint32_t> fresh = new_candidates(centres, caps);
  std::sort(fresh.begin(), fresh.end(), [&](auto a, auto b) { return balls_[a].R > balls_[b].R; });
  std::vector<std::uint32_t> taken;
  for (const auto b : fresh) {
    const Eigen::Vector3d& c = P_[balls_[b].centre];
    const std::uint32_t f = face[b - first];
    if (balls_[b].face >= 0 || !balls_[b].is_bounded || balls_[b].R < opt_.view_ball_min_reach * faces_->reach[f]) {
      small.push_back({f, c});
      continue;
    }
    if (!near_taken(b, taken)) take_pinned(b, taken);
  }
  return taken.size();
}

// The spots join the points, uncovered, on their faces with their faces' normals.
void SlimFitter::add_points(const std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>& spots) {
  const std::size_t n0 = P_.size();
  for (const auto& [f, x] : spots) {
    owned_.points.push_back(x);
    N_.push_back(N_[faces_->centroid[f]]);
    faces_->face_of.push_back(f);
  }
  const std::size_t n1 = P_.size();
  const std::vector<double> h = probe_heights(std::span<const Eigen::Vector3d>(P_).subspan(n0),
                                              std::span<const Eigen::Vector3d>(N_).subspan(n0), opt_.probe_factor * E_, data_.get());
  probe_height_.insert(probe_height_.end(), h.begin(), h.end());
  covered_.resize(n1, 0);
  cap_.resize(n1, kInf);
  point_error_.resize(n1, kInf);
  point_reach_.resize(n1, kInf);
  other_direction_.resize(n1, 0);
  for (std::size_t i = n0; i < n1; ++i) order_.push_back(std::uint32_t(i));
  index_ = std::make_unique<PointIndex>(P_);
  make_fitter();
  st_.hole_points += n1 - n0;
}

// Points side: every point's probe against the blended surface (core/reference.h).
// Culprits: patches whose own hit in the blend is farther than E, or whose ball holds a
// point the blend misses.
std::size_t SlimFitter::verify_points(const ReferenceScene& scene, const PointIndex& centres, const std::vector<std::uint8_t>& stale,
                          std::vector<std::uint8_t>& at_fault) {
  const std::size_t n = P_.size();
  point_error_.resize(n, kInf);
  point_reach_.resize(n, kInf);
  other_direction_.resize(n, 0);
  const auto& slims = result_.model.slims;
  double max_radius = 0;
  for (const auto& s : slims) max_radius = std::max(max_radius, s.radius);
  TraceOptions trace;
  trace.slim = blend();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 512), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<SlimSample> blended;
    std::vector<Neighbour> near;
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      if (!stale[i]) continue;
      const double h = probe_height_[i];
      bool other = false;
      const PointProbe probe = measure_point(scene, trace, *index_, N_, P_[i], N_[i], h, E_, &blended, &other);
      // Measured along its neighbourhood's normal: traced again in every round (staleness
      // follows the first ray only).
      other_direction_[i] = other;
      point_error_[i] = probe.error;
      point_reach_[i] = probe.reach;
      if (!std::isfinite(probe.error)) {
        centres.radius(P_[i], max_radius, near);
        for (const auto& [k, d2] : near)
          if (d2 <= slims[k].radius * slims[k].radius) at_fault[k] = 1;  // benign race: all store 1
        continue;
      }
      if (probe.error > E_)
        for (const auto& s : blended)
          if (std::abs(s.hit.t - h) > E_) at_fault[static_cast<std::size_t>(s.index)] = 1;
    }
  });
  std::size_t failing = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (!(point_error_[i] <= E_) && ++failing <= 8)
      log::debug("fit_slim: a point at ({:.6g}, {:.6g}, {:.6g}) normal ({:.3f}, {:.3f}, {:.3f}): {:.3g} E from the surface",
                 P_[i].x(), P_[i].y(), P_[i].z(), N_[i].x(), N_[i].y(), N_[i].z(), point_error_[i] / E_);
  return failing;
}

// The chosen patches' surface-sample distances, all in one list (the figures' source).
void SlimFitter::collect_surface_errors() {
  surface_error_.clear();
  for (const auto b : chosen_) surface_error_.insert(surface_error_.end(), patch_errors_[b].begin(), patch_errors_[b].end());
}

// The slanted views of a patch's rim point (verify_surface): kRimViews directions towards the
// viewer's side of its sheet, 50° and 70° from its normal, six azimuths each from the rim's
// outward direction.
namespace {
constexpr int kRimViews = 12;
std::array<Eigen::Vector3d, kRimViews> rim_views(const SlimPatch& patch, const SlimSurfaceSample& z) {
  const Eigen::Vector3d& n = z.normal;
  Eigen::Vector3d out = z.point - patch.centre;
  out -= out.dot(n) * n;
  out = out.squaredNorm() > 0 ? out.normalized() : n.unitOrthogonal();
  const Eigen::Vector3d side = n.cross(out);
  std::array<Eigen::Vector3d, kRimViews> views;
  for (int v = 0; v < kRimViews; ++v) {
    const double tilt = (v < kRimViews / 2 ? 50.0 : 70.0) * std::numbers::pi / 180.0;
    const double azimuth = (v % (kRimViews / 2)) * 2.0 * std::numbers::pi / (kRimViews / 2);
    views[v] = std::cos(tilt) * n + std::sin(tilt) * (std::cos(azimuth) * out + std::sin(azimuth) * side);
  }
  return views;
}
}  // namespace

// Surface side: samples of every patch's zero set, each seen along its normal through the
// blend (a rim point off the data also from the side, rim_views); the blended point must lie
// within surface_factor·E of the data. Culprits: the blended patches whose own hit is farther
// than local_surface_factor·E (all of them when none is).
std::size_t SlimFitter::verify_surface(const ReferenceScene& scene, const std::vector<std::uint8_t>& stale,
                           std::vector<std::uint8_t>& at_fault) {
  debug_shown_ = 0;
  const auto& slims = result_.model.slims;
  const double bound = opt_.surface_factor * E_, local = opt_.local_surface_factor * E_;
  const double h = opt_.surface_probe_factor * E_;
  TraceOptions trace;
  trace.slim = blend();
  shrink_.assign(slims.size(), opt_.shrink_step);
  patch_excess_.resize(balls_.size(), -1.0);
  patch_errors_.resize(balls_.size());
  patch_reach_.resize(balls_.size(), kInf);
  rim_off_.resize(balls_.size());
  rim_known_.resize(balls_.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, slims.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<SlimSurfaceSample> zero, rim;
    std::vector<SlimSample> blended;
    for (std::size_t k = r.begin(); k != r.end(); ++k) {
      if (!stale[k]) continue;
      auto& errors = patch_errors_[chosen_[k]];
      double& reach = patch_reach_[chosen_[k]];
      errors.clear();
      reach = 0;
      // The patch alone on a lattice fine in world units (≈ verify_spacing·E), so slivers
      // past a curved boundary are found on large balls too; a patch found d > bound away
      // shrinks by √(bound/d) (a sliver's sagitta goes with R²).
      const int grid = std::clamp(static_cast<int>(std::ceil(2.0 * slims[k].radius / (opt_.verify_spacing * E_))),
                                  opt_.verify_surface_grid, opt_.verify_max_grid);
      // A patch's own zero set does not change between rounds: checked once per candidate ball.
      double& excess = patch_excess_[chosen_[k]];
      // Skipped when settle's check already passed on a lattice at least as fine (same bound).
      const Ball& ball = balls_[chosen_[k]];
      if (excess < 0)
        excess = grid <= ball.surface_lattice || ball.on_data ? 0.0 : zero_set_excess(slims[k], *data_, local, grid, 1);
      if (const double d = excess; d > 0) {
        if (log::level() <= log::Level::debug) {
          const std::lock_guard lock(debug_mutex_);
          if (++debug_shown_ <= 8)
            log::debug("fit_slim: patch {}{} (ball {}, R {:.3g}E) runs {:.3g}E from the data inside its ball", k,
                       ball.face >= 0 ? " (face)" : ball.disc ? " (disc)" : "", chosen_[k], slims[k].radius / E_, d / E_);
        }
        at_fault[k] = 1;
        errors.push_back(d);
        reach = kInf;
        shrink_[k] = std::clamp(std::sqrt(local / d), 0.3, opt_.shrink_step);
        continue;
      }
      zero.clear();
      sample_slim_patch(slims[k], opt_.verify_surface_grid, zero);
      // The rim every E/2: its points off the data are seen through the blend too (elsewhere
      // other patches hide it, or the lattice samples above vouch for the blend).
      // Which of them lie off the data does not change between rounds either: found once per
      // candidate ball.
      if (!rim_known_[chosen_[k]]) {
        rim.clear();
        if (!ball.on_data) {
          sample_slim_rim(slims[k], 0.5 * E_, rim);
          sample_slim_rim_at_axes(slims[k], rim);
        }
        auto& off = rim_off_[chosen_[k]];
        off.clear();
        for (const auto& z : rim)
          if (!(data_->distance(z.point, bound, bound) <= bound)) off.push_back(z);
        rim_known_[chosen_[k]] = 1;
      }
      const std::size_t lattice = zero.size();
      zero.insert(zero.end(), rim_off_[chosen_[k]].begin(), rim_off_[chosen_[k]].end());
      for (std::size_t si = 0; si < zero.size(); ++si) {
        const auto& z = zero[si];
        // A rim point off the data is seen along its normal and along kRimViews slanted views:
        // where the blend shows it alone from the side, it is a fin there though a patch over
        // it hides it head-on (a raw scan's fin at 1e-2, 5E off, seen 57–69° from its normal).
        const int views = si < lattice ? 1 : 1 + kRimViews;
        const auto slanted = si < lattice ? std::array<Eigen::Vector3d, kRimViews>{} : rim_views(slims[k], z);
        double d = -1;
        for (int v = 0; v < views && !(d > bound); ++v) {
          const Eigen::Vector3d w = v == 0 ? z.normal : slanted[v - 1];
          const auto hit = scene.trace(Ray{z.point + h * w, -w}, 0.0, kInf, trace, &blended);
          if (!hit) continue;
          if (v == 0) reach = std::max(reach, blend_reach(blended, trace.slim));
          double dv = data_->distance(hit->point, bound);
          if (!(dv <= bound)) dv = data_->distance(hit->point);
          d = std::max(d, dv);
        }
        if (d < 0) continue;
        errors.push_back(d);
        if (d <= bound) continue;
        reach = kInf;
        if (log::level() <= log::Level::debug) {
          const std::lock_guard lock(debug_mutex_);
          if (++debug_shown_ <= 8) {
            std::string who;
            for (const auto& sb : blended) {
              const Ball& bb = balls_[chosen_[static_cast<std::size_t>(sb.index)]];
              who += fmt::format(" [{}{} R {:.3g}E w {:.2g} t-h {:.3g}E data {:.3g}E]", sb.index, bb.face >= 0 ? " face" : bb.disc ? " disc" : "",
                                 sb.radius / E_, sb.weight, (sb.hit.t - h) / E_, data_->distance(sb.hit.point) / E_);
            }
            log::debug("fit_slim: surface sample of patch {}{} (R {:.3g}E) at ({:.6g}, {:.6g}, {:.6g}): blend {:.3g}E from the data;{}", k,
                       balls_[chosen_[k]].face >= 0 ? " (face)" : "", slims[k].radius / E_, z.point.x(), z.point.y(), z.point.z(), d / E_, who);
          }
        }
        bool blamed = false;
        for (const auto& s : blended)
          if (data_->distance(s.hit.point, local) > local) at_fault[static_cast<std::size_t>(s.index)] = 1, blamed = true;
        if (!blamed)
          for (const auto& s : blended) at_fault[static_cast<std::size_t>(s.index)] = 1;
      }
    }
  });
  collect_surface_errors();
  std::size_t failing = 0;
  for (const double e : surface_error_) failing += e > bound;
  return failing;
}

SlimFitter::Changed SlimFitter::changed_since(const std::vector<std::uint32_t>& before) const {
  std::vector<std::uint8_t> was(balls_.size(), 0), is(balls_.size(), 0);
  for (const auto b : before) was[b] = 1;
  for (const auto b : chosen_) is[b] = 1;
  Changed c;
  for (std::size_t b = 0; b < balls_.size(); ++b)
    if (was[b] != is[b]) {
      c.centres.push_back(P_[balls_[b].centre]);
      c.radii.push_back(balls_[b].R);
      c.max_radius = std::max(c.max_radius, balls_[b].R);
    }
  c.index = std::make_unique<PointIndex>(std::span<const Eigen::Vector3d>(c.centres));
  return c;
}

}  // namespace quadrix::fit_detail
