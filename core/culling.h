#pragma once
/// When backface culling leaves an image unchanged (DESIGN §6: culling is conservative, it never
/// removes a patch some ray from the eye can hit). Per-fragment culling (front-facing roots only,
/// [Stoll06] eq. 14) and the per-quadric tests (eq. 18, 19) hide the back side of every patch, so
/// for tetrahedron patches and glyphs they are exact only where the back sides cannot be seen:
/// the patches bound a solid (a closed surface, gradients pointing out) and the eye is outside
/// it. Open surfaces (a quad sheet, a scan with boundaries, a volume's iso-surface cut by the
/// volume's edge) are two-sided: they are never culled. SLIM patches are one-sided by definition
/// (the blend takes front-facing hits only, core/slim.h), so their per-quadric test is always exact.
#include "core/camera.h"
#include "core/model.h"

namespace quadrix {

/// Model metadata key: "1" when the model's tetrahedron patches and glyphs bound solids with
/// outward gradients (written by convert quads for closed, outward-oriented meshes, and by
/// convert skin). Absent: two-sided.
inline constexpr const char* kClosedKey = "closed";

/// True when the model says its non-SLIM surfaces are closed (kClosedKey), or it has none.
bool surfaces_are_closed(const Model& model);

/// True when culling back sides cannot change what the camera sees of a model whose non-SLIM
/// surfaces are `closed` and lie inside `box` (world units): closed, and the box lies wholly
/// beyond the near plane (so the eye, and the near plane's cut, are outside every solid).
bool backface_culling_is_exact(const Box3& box, bool closed, const Camera& camera);

/// The same for a whole model (computes its bounds).
bool backface_culling_is_exact(const Model& model, const Camera& camera);

}  // namespace quadrix
