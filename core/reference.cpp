#include "core/reference.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "core/bounds.h"
#include "core/bvh.h"
#include "core/culling.h"
#include "core/error.h"
#include "core/implicit/surface.h"
#include "core/lighting.h"

namespace quadrix {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Barycentric tolerance for tetrahedron clipping: neighbours sharing a face both accept a hit
// on it, so no pixel falls through the crack between them.
constexpr double kTetEps = 1e-9;

struct PreparedTet {
  Tetrahedron tet;
  Eigen::Vector3d centroid;
  Quadric local;  // f(y + centroid)
};

struct PreparedGlyph {
  Eigen::Vector3d centre;
  Quadric local;  // f(y + centre)
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();  // cylinder: unit axis
  double half_length = 0, radius = 0;
  GlyphKind kind;
};

struct Ref {
  PrimitiveKind kind;
  std::uint32_t index;
};

PreparedGlyph prepare(const Glyph& g) {
  PreparedGlyph p;
  p.centre = g.centre;
  p.kind = g.kind;
  switch (g.kind) {
    case GlyphKind::sphere: p.local = Quadric::sphere(Eigen::Vector3d::Zero(), g.radius); break;
    case GlyphKind::ellipsoid: {
      // x = M u, ‖u‖ = 1  ⇔  xᵀ M⁻ᵀM⁻¹ x − 1 = 0.
      const Eigen::Matrix3d Mi = g.axes.inverse();
      p.local.A = Mi.transpose() * Mi;
      p.local.c = -1.0;
      break;
    }
    case GlyphKind::cylinder: {
      const Eigen::Vector3d a = g.axes.col(0);
      p.half_length = a.norm();
      p.axis = a / p.half_length;
      p.radius = g.radius;
      // ‖x − (x·â)â‖² − r² = xᵀ(I − ââᵀ)x − r².
      p.local.A = Eigen::Matrix3d::Identity() - p.axis * p.axis.transpose();
      p.local.c = -g.radius * g.radius;
      break;
    }
  }
  return p;
}

// Corner colours at barycentric coordinates b (clamped to the tetrahedron), rounded.
Rgb interpolate_colour(const std::array<Rgb, 4>& c, const Eigen::Vector4d& b) {
  const Eigen::Vector4d w = b.cwiseMax(0.0) / std::max(1e-300, b.cwiseMax(0.0).sum());
  Rgb out;
  for (int ch = 0; ch < 3; ++ch) {
    double v = 0;
    for (int k = 0; k < 4; ++k) v += w[k] * c[k][ch];
    out[ch] = static_cast<std::uint8_t>(std::clamp(v + 0.5, 0.0, 255.0));
  }
  return out;
}

}  // namespace

struct ReferenceScene::Impl {
  const Model* model;
  std::vector<PreparedTet> tets;
  std::vector<PreparedGlyph> glyphs;
  std::vector<implicit::CompiledImplicit> implicits;
  std::vector<Ref> refs;
  Bvh bvh;

  // Implicits are two-sided: the first root, guaranteed by interval isolation, whatever its facing.
  bool hit_implicit(const implicit::CompiledImplicit& s, const Ray& ray, double tmin, double tmax, Hit& hit) const {
    const auto root = implicit::first_root(s, ray, tmin, tmax);
    if (!root) return false;
    hit.t = root->t;
    hit.point = ray.at(root->t);
    hit.gradient = s.expression.value_gradient(hit.point, s.parameters).gradient;
    if (!hit.gradient.allFinite()) hit.gradient.setZero();
    hit.front_facing = hit.gradient.dot(ray.dir) <= 0;
    return true;
  }

  bool hit_tet(const PreparedTet& p, const Ray& ray, double tmin, double tmax, bool cull, Hit& hit) const {
    Ray local;
    const double t0 = rebase_ray(ray, p.centroid, local);
    const auto inside = [&](const Eigen::Vector3d& y) { return p.tet.contains(y + p.centroid, kTetEps); };
    if (!intersect_quadric(p.local, local, tmin - t0, tmax - t0, cull, inside, hit)) return false;
    hit.t += t0;
    hit.point = ray.at(hit.t);
    return true;
  }

  bool hit_glyph(const PreparedGlyph& p, const Ray& ray, double tmin, double tmax, bool cull, Hit& hit) const {
    Ray local;
    const double t0 = rebase_ray(ray, p.centre, local);
    bool found = false;
    if (p.kind != GlyphKind::cylinder) {
      found = intersect_quadric(p.local, local, tmin - t0, tmax - t0, cull, [](const auto&) { return true; }, hit);
    } else {
      const auto inside = [&](const Eigen::Vector3d& y) { return std::abs(y.dot(p.axis)) <= p.half_length; };
      found = intersect_quadric(p.local, local, tmin - t0, tmax - t0, cull, inside, hit);
      // Flat end caps: planes ±â·y = h with outward normals ±â.
      const double dn = local.dir.dot(p.axis);
      if (dn != 0.0) {
        for (const double s : {1.0, -1.0}) {
          const double t = (s * p.half_length - local.origin.dot(p.axis)) / dn;
          const double upper = found ? hit.t : tmax - t0;
          if (!(t > tmin - t0 && t < upper)) continue;
          const bool front = s * dn < 0.0;
          if (cull && !front) continue;
          const Eigen::Vector3d y = local.at(t);
          if ((y - y.dot(p.axis) * p.axis).squaredNorm() > p.radius * p.radius) continue;
          hit.t = t;
          hit.point = y;
          hit.gradient = s * p.axis;
          hit.front_facing = front;
          found = true;
        }
      }
    }
    if (!found) return false;
    hit.t += t0;
    hit.point = ray.at(hit.t);
    return true;
  }
};

ReferenceScene::ReferenceScene(const Model& model) : impl_(std::make_unique<Impl>()) {
  impl_->model = &model;
  std::vector<Box3> boxes;
  boxes.reserve(model.size());
  for (std::uint32_t i = 0; i < model.slims.size(); ++i) {
    impl_->refs.push_back({PrimitiveKind::slim, i});
    boxes.push_back(bounds(model.slims[i]));
  }
  impl_->tets.reserve(model.tets.size());
  for (std::uint32_t i = 0; i < model.tets.size(); ++i) {
    const auto& t = model.tets[i];
    impl_->tets.push_back({Tetrahedron(t.corners), t.centroid(), t.quadric});
    impl_->refs.push_back({PrimitiveKind::tet, i});
    boxes.push_back(bounds(t));
  }
  impl_->glyphs.reserve(model.glyphs.size());
  for (std::uint32_t i = 0; i < model.glyphs.size(); ++i) {
    impl_->glyphs.push_back(prepare(model.glyphs[i]));
    impl_->refs.push_back({PrimitiveKind::glyph, i});
    boxes.push_back(bounds(model.glyphs[i]));
  }
  impl_->implicits.reserve(model.implicits.size());
  for (std::uint32_t i = 0; i < model.implicits.size(); ++i) {
    impl_->implicits.push_back(implicit::compile(model.implicits[i]));
    impl_->refs.push_back({PrimitiveKind::implicit, i});
    boxes.push_back(model.implicits[i].bounds);
  }
  impl_->bvh = Bvh(boxes);
}

ReferenceScene::~ReferenceScene() = default;
ReferenceScene::ReferenceScene(ReferenceScene&&) noexcept = default;
ReferenceScene& ReferenceScene::operator=(ReferenceScene&&) noexcept = default;
const Model& ReferenceScene::model() const { return *impl_->model; }
std::size_t ReferenceScene::bvh_node_count() const { return impl_->bvh.nodes().size(); }

std::optional<SurfaceHit> ReferenceScene::trace(const Ray& ray, double tmin, double tmax,
                                                const TraceOptions& options, std::vector<SlimSample>* blended) const {
  if (blended) blended->clear();
  const Model& m = *impl_->model;
  double best_t = tmax;  // nearest opaque (tet, glyph) hit so far
  Hit best;
  Ref best_ref{PrimitiveKind::none, 0};
  double t_cut = kInf;  // SLIM pass-1 depth: min(tᵢ + pushᵢ)
  // Small inline buffer: most rays meet a handful of patches.
  std::vector<SlimSample> samples;
  const auto bound = [&] { return std::min(best_t, t_cut); };
  impl_->bvh.traverse(ray, tmin, bound, [&](std::uint32_t item) {
    const Ref r = impl_->refs[item];
    Hit h;
    switch (r.kind) {
      case PrimitiveKind::slim: {
        const SlimPatch& p = m.slims[r.index];
        if (!intersect_slim_patch(p, ray, tmin, best_t, h)) return;
        const double w = slim_weight((h.point - p.centre).norm() / p.radius);
        const double own = p.max_push.value_or(-1.0);
        samples.push_back({h, w, p.radius, static_cast<int>(r.index), own});
        t_cut = std::min(t_cut, h.t + options.slim.push(p.radius, own));
        return;
      }
      case PrimitiveKind::tet:
        if (!impl_->hit_tet(impl_->tets[r.index], ray, tmin, best_t, options.cull_backfaces, h)) return;
        break;
      case PrimitiveKind::glyph:
        if (!impl_->hit_glyph(impl_->glyphs[r.index], ray, tmin, best_t, options.cull_backfaces, h)) return;
        break;
      case PrimitiveKind::implicit:
        if (!impl_->hit_implicit(impl_->implicits[r.index], ray, tmin, best_t, h)) return;
        break;
      case PrimitiveKind::none:
      case PrimitiveKind::mesh: return;  // the reference traces no meshes
    }
    best_t = h.t;
    best = h;
    best_ref = r;
  });

  SurfaceHit out;
  if (!samples.empty()) {
    // Only patch hits in front of the nearest opaque surface take part (they share one depth test).
    std::erase_if(samples, [&](const SlimSample& s) { return s.hit.t >= best_t; });
    thread_local std::vector<SlimSample> used_here;
    std::vector<SlimSample>* used = blended ? blended : &used_here;
    if (const auto b = blend_slim_samples(samples, options.slim, used); b && b->t < best_t) {
      out.t = b->t;
      out.point = b->point;
      out.normal = b->normal;
      out.kind = PrimitiveKind::slim;
      out.index = b->first_index;
      // The colour is blended like the position (Σwᵢcᵢ / Σwᵢ), as the GL accumulation pass does.
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      double w = 0;
      for (const SlimSample& s : *used) {
        const Rgb ci = m.slims[s.index].colour.value_or(out.colour);
        c += s.weight * Eigen::Vector3d(ci[0], ci[1], ci[2]);
        w += s.weight;
      }
      if (w > 0)
        for (int k = 0; k < 3; ++k) out.colour[k] = static_cast<std::uint8_t>(std::clamp(c[k] / w, 0.0, 255.0) + 0.5);
      return out;
    }
    if (blended) blended->clear();  // the blend lies behind an opaque surface
  }
  if (best_ref.kind == PrimitiveKind::none) return std::nullopt;
  out.t = best.t;
  out.point = best.point;
  const double g = best.gradient.norm();
  out.normal = g > 0 ? Eigen::Vector3d(best.gradient / g) : Eigen::Vector3d(-ray.dir.normalized());
  if (out.normal.dot(ray.dir) > 0) out.normal = -out.normal;  // two-sided: face the viewer
  out.kind = best_ref.kind;
  out.index = static_cast<int>(best_ref.index);
  const std::optional<Rgb>& colour = best_ref.kind == PrimitiveKind::tet        ? m.tets[best_ref.index].colour
                                     : best_ref.kind == PrimitiveKind::implicit ? m.implicits[best_ref.index].colour
                                                                                : m.glyphs[best_ref.index].colour;
  if (colour) out.colour = *colour;
  if (best_ref.kind == PrimitiveKind::tet && m.tets[best_ref.index].corner_colours)
    out.colour = interpolate_colour(*m.tets[best_ref.index].corner_colours,
                                    impl_->tets[best_ref.index].tet.barycentric(out.point));
  return out;
}

ReferenceImage render_reference(const ReferenceScene& scene, const Camera& camera,
                                const ReferenceRenderOptions& options) {
  if (camera.width <= 0 || camera.height <= 0 || camera.width > 16384 || camera.height > 16384)
    throw InvalidInput("image size must be between 1 and 16384 pixels per side");
  ReferenceImage img;
  img.width = camera.width;
  img.height = camera.height;
  const std::size_t n = static_cast<std::size_t>(img.width) * img.height;
  img.coverage.assign(n, 0);
  img.depth.assign(n, std::numeric_limits<float>::infinity());
  img.distance.assign(n, std::numeric_limits<float>::infinity());
  img.normal.assign(n, Eigen::Vector3f::Zero());
  img.primitive.assign(n, -1);
  img.albedo.assign(n, Rgb{0, 0, 0});
  const Box3 box = bounds(scene.model());
  img.scene_radius = box.empty() ? 0.0 : 0.5 * box.diagonal();
  if (options.shadows && !box.empty()) img.key_light.assign(n, 1.0f);
  const Eigen::Vector3d light = img.key_light.empty() ? Eigen::Vector3d::Zero() : shadow_light_camera(camera, box, 1).eye;
  // Shadow rays leave the surface by this much (the GL map's bias is of the order of a texel).
  const double shadow_eps = 1e-3 * img.scene_radius;
  TraceOptions shadow_trace = options.trace;
  shadow_trace.cull_backfaces = false;  // rays start on surfaces, inside closed solids' shells
  const Eigen::Vector3d fwd = camera.forward();
  // Back sides are culled only where no ray from the eye can see them (core/culling.h).
  TraceOptions trace = options.trace;
  trace.cull_backfaces = trace.cull_backfaces && backface_culling_is_exact(scene.model(), camera);
  std::atomic<int> rows_done{0};
  tbb::parallel_for(tbb::blocked_range<int>(0, img.height, 4), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y) {
      for (int x = 0; x < img.width; ++x) {
        const Ray ray = camera.pixel_ray(x + 0.5, y + 0.5);
        // From the near plane on, as the GL passes see (rasterised proxies clipped there, ray casts
        // skipping hits in front of it): a glyph the near plane cuts shows its far side.
        const auto hit = scene.trace(ray, camera.near_plane / ray.dir.dot(fwd), kInf, trace);
        if (!hit) continue;
        const std::size_t i = static_cast<std::size_t>(y) * img.width + x;
        img.coverage[i] = 1;
        img.distance[i] = static_cast<float>(hit->t);
        img.depth[i] = static_cast<float>(hit->t * ray.dir.dot(fwd));
        img.normal[i] = hit->normal.cast<float>();
        img.primitive[i] = primitive_id(hit->kind, static_cast<std::size_t>(hit->index));
        img.albedo[i] = hit->colour;
        if (!img.key_light.empty()) {
          const Eigen::Vector3d to_light = light - hit->point;
          const double distance = to_light.norm();
          const Eigen::Vector3d dir = to_light / distance;
          const Eigen::Vector3d lift = (hit->normal.dot(dir) >= 0 ? shadow_eps : -shadow_eps) * hit->normal;
          if (scene.trace(Ray{hit->point + lift, dir}, shadow_eps, distance, shadow_trace)) img.key_light[i] = 0.0f;
        }
      }
    }
    const int done = rows_done += static_cast<int>(rows.size());
    if (options.progress) options.progress(static_cast<double>(done) / img.height);
  });
  return img;
}

double line_distance(const ReferenceScene& scene, const TraceOptions& trace, const Eigen::Vector3d& p,
                     const Eigen::Vector3d& d, double reach) {
  double best = -1.0;
  for (const double side : {1.0, -1.0}) {
    const Ray ray{p + side * reach * d, -side * d};
    double tmin = 0.0;
    for (int k = 0; k < 4; ++k) {
      const auto hit = scene.trace(ray, tmin, 2.0 * reach, trace);
      if (!hit) break;
      const double dist = std::abs(hit->t - reach);
      if (best < 0 || dist < best) best = dist;
      if (hit->t >= reach) break;  // later hits are farther from p
      tmin = hit->t + 1e-9 * reach;
    }
    if (best == 0.0) break;
  }
  return best;
}

double nearest_along_lines(const ReferenceScene& scene, const TraceOptions& trace, const Eigen::Vector3d& p,
                           const Eigen::Vector3d& n, double reach, double bound) {
  static const std::vector<Eigen::Vector3d> kLines = [] {
    std::vector<Eigen::Vector3d> v;
    for (int x = -1; x <= 1; ++x)
      for (int y = -1; y <= 1; ++y)
        for (int z = -1; z <= 1; ++z)
          if (Eigen::Vector3i c(x, y, z); c.squaredNorm() > 0 && c.dot(Eigen::Vector3i(9, 3, 1)) > 0)  // one per line
            v.push_back(c.cast<double>().normalized());
    return v;
  }();
  double d = line_distance(scene, trace, p, n, reach);
  for (const Eigen::Vector3d& dir : kLines) {
    if (d >= 0 && d <= bound) break;
    const double dq = line_distance(scene, trace, p, dir, reach);
    if (dq >= 0 && (d < 0 || dq < d)) d = dq;
  }
  return d;
}

}  // namespace quadrix
