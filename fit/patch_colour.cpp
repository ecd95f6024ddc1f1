#include "fit/patch_colour.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/error.h"
#include "core/slim.h"
#include "fit/point_index.h"

namespace quadrix {

void set_patch_colours(Model& model, const PointCloud& cloud) {
  if (!cloud.has_colours()) return;
  if (cloud.colours.size() != cloud.points.size())
    throw InvalidInput(fmt::format("patch colours: {} colours for {} points", cloud.colours.size(), cloud.points.size()));
  const PointIndex index(cloud.points);
  const auto colour = [&](std::vector<SlimPatch>& balls) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, balls.size(), 64), [&](const tbb::blocked_range<std::size_t>& r) {
      std::vector<Neighbour> nb;
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        SlimPatch& b = balls[i];
        index.radius(b.centre, b.radius, nb);
        std::array<double, 3> sum{};
        double wsum = 0;
        for (const auto& [j, d2] : nb) {
          const double w = slim_weight(std::sqrt(d2) / b.radius);
          for (int k = 0; k < 3; ++k) sum[k] += w * cloud.colours[j][k];
          wsum += w;
        }
        if (!(wsum > 0)) {
          index.nearest(b.centre, 1, nb);
          if (nb.empty()) continue;
          b.colour = cloud.colours[nb[0].first];
          continue;
        }
        Rgb c{};
        for (int k = 0; k < 3; ++k) c[k] = static_cast<std::uint8_t>(std::clamp(std::round(sum[k] / wsum), 0.0, 255.0));
        b.colour = c;
      }
    });
  };
  colour(model.slims);
  colour(model.slim_hierarchy.others);
}

}  // namespace quadrix
