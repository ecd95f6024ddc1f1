#pragma once
/// The built-in surfaces of [Singh10]'s appendix (Table I): algebraic ones from cubics to the
/// Chmutov surfaces of order 50 (power, iterative Chebyshev and trigonometric Chebyshev forms),
/// and non-algebraic ones (torus, superquadric, blobbies, Scherk, diamond).
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/model.h"

namespace quadrix::implicit {

struct GalleryEntry {
  std::string name;
  std::string description;  ///< name in the paper, order in brackets
  ImplicitSurface surface;
  /// The root test the AMP renderer needs here: "sign", or "taylor" where roots are multiple
  /// (singular lines, [Singh10] Fig. 6).
  std::string test = "sign";
  /// [Singh10] Table I step size (its surfaces are about 2–4 units across), 0 if not listed.
  double paper_step = 0;
};

/// Every built-in surface, in the order of the paper's appendix. Named forms with an order
/// (chmutov-iter-50, blinn-75) are also accepted by gallery_surface for other orders.
std::vector<GalleryEntry> gallery();

/// The entry called `name`: a gallery name, or chmutov-N / chmutov-iter-N / chmutov-trig-N
/// (N = 2…1000) or blinn-N (N = 1…1000 balls). \throws InvalidInput naming the known ones.
GalleryEntry gallery_surface(std::string_view name);

}  // namespace quadrix::implicit
