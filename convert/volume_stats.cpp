#include "convert/volume_stats.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "core/error.h"

namespace quadrix {
namespace {

// Bin of v among `bins` equal bins over [lo, hi], the last one closed.
std::size_t bin_of(double v, double lo, double hi, std::size_t bins) {
  const double t = (v - lo) / (hi - lo) * double(bins);
  return std::min(bins - 1, static_cast<std::size_t>(std::max(0.0, t)));
}

// Between-class variance (up to a constant factor) of the classes split at the given boundaries
// (bin indices, increasing): Σ_k ω_k μ_k² over the classes, with prefix sums of counts and of
// count·centre; the total mean term is the same for every split and left out.
struct Prefix {
  std::vector<double> w, m;  // w[i] = Σ_{b<i} count, m[i] = Σ_{b<i} count·b
  explicit Prefix(const std::vector<std::size_t>& h) : w(h.size() + 1, 0.0), m(h.size() + 1, 0.0) {
    for (std::size_t b = 0; b < h.size(); ++b) {
      w[b + 1] = w[b] + double(h[b]);
      m[b + 1] = m[b] + double(h[b]) * (double(b) + 0.5);
    }
  }
  double term(std::size_t from, std::size_t to) const {  // class of bins [from, to)
    const double ww = w[to] - w[from];
    return ww > 0 ? (m[to] - m[from]) * (m[to] - m[from]) / ww : 0.0;
  }
};

// The first maximum of score, moved to the middle of the run of equal scores that starts there
// (an empty stretch of bins between two classes gives the same split at every boundary in it).
double middle_of_ties(const std::vector<double>& score, std::size_t first) {
  const std::size_t lo = std::size_t(std::max_element(score.begin(), score.end()) - score.begin());
  const double tol = 1e-12 * std::max(1.0, std::abs(score[lo]));
  std::size_t end = lo;
  while (end + 1 < score.size() && score[end + 1] >= score[lo] - tol) ++end;
  return double(first + lo) + 0.5 * double(end - lo);
}

}  // namespace

double otsu_threshold(const std::vector<std::size_t>& h, double lo, double hi) {
  if (h.size() < 2) return lo;
  const Prefix p(h);
  // Boundary k (1 ≤ k < bins): classes [0, k) and [k, bins).
  std::vector<double> score(h.size() - 1);
  for (std::size_t k = 1; k < h.size(); ++k) score[k - 1] = p.term(0, k) + p.term(k, h.size());
  const double k = middle_of_ties(score, 1);
  return lo + (hi - lo) * k / double(h.size());
}

VolumeStats volume_stats(const Volume& v, const VolumeStatsOptions& o) {
  if (v.values.empty()) throw InvalidInput(fmt::format("{}: the volume holds no samples", v.source));
  if (o.otsu_bins < 2 || o.histogram_bins < 1)
    throw InvalidInput(fmt::format("volume statistics: {} Otsu bins and {} histogram bins (need ≥ 2 and ≥ 1)", o.otsu_bins,
                                   o.histogram_bins));
  VolumeStats s;
  s.samples = v.values.size();
  double sum = 0;
  s.min = std::numeric_limits<double>::infinity();
  s.max = -s.min;
  for (std::size_t i = 0; i < v.values.size(); ++i) {
    const double x = v.values[i];
    if (!std::isfinite(x)) throw InvalidInput(fmt::format("{}: sample {} is not finite ({})", v.source, i, x));
    s.min = std::min(s.min, x), s.max = std::max(s.max, x);
    sum += x;
  }
  s.mean = sum / double(s.samples);
  double ss = 0;
  for (const float x : v.values) ss += (x - s.mean) * (x - s.mean);
  s.stddev = std::sqrt(ss / double(s.samples));

  // Percentiles by nearest rank over all samples.
  {
    std::vector<float> sorted(v.values);
    for (const double pc : o.percentiles) {
      if (!(pc >= 0 && pc <= 100)) throw InvalidInput(fmt::format("volume statistics: percentile {} is not in [0, 100]", pc));
      const auto rank = static_cast<std::size_t>(std::ceil(pc / 100.0 * double(s.samples)));
      const std::size_t k = rank == 0 ? 0 : rank - 1;
      std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(k), sorted.end());
      s.percentiles.emplace_back(pc, sorted[k]);
    }
  }
  s.histogram.assign(std::size_t(o.histogram_bins), 0);
  if (!(s.max > s.min)) {
    s.histogram[0] = s.samples;
    return s;
  }
  std::vector<std::size_t> fine(std::size_t(o.otsu_bins), 0);
  for (const float x : v.values) {
    ++s.histogram[bin_of(x, s.min, s.max, s.histogram.size())];
    ++fine[bin_of(x, s.min, s.max, fine.size())];
  }
  const auto below = [&](double t) {
    return double(std::count_if(v.values.begin(), v.values.end(), [t](float x) { return x < t; })) / double(s.samples);
  };
  const auto inside = [&](double t) {  // strictly inside (min, max)
    const double eps = 1e-6 * (s.max - s.min);
    return std::clamp(t, s.min + eps, s.max - eps);
  };
  const double t2 = inside(otsu_threshold(fine, s.min, s.max));
  s.suggestions.push_back({"otsu", t2, below(t2)});
  // Three classes: boundaries j < k maximising Σ ω μ² over the three (O(bins²)).
  const Prefix p(fine);
  const std::size_t n = fine.size();
  double best = -1;
  std::size_t bj = 1, bk = 2;
  for (std::size_t j = 1; j + 1 < n; ++j)
    for (std::size_t k = j + 1; k < n; ++k)
      if (const double sc = p.term(0, j) + p.term(j, k) + p.term(k, n); sc > best * (1 + 1e-12)) best = sc, bj = j, bk = k;
  // Each boundary moved to the middle of its run of equal scores (an empty gap), as for two classes.
  const auto score3 = [&](std::size_t j, std::size_t k) { return p.term(0, j) + p.term(j, k) + p.term(k, n); };
  const double tol = 1e-12 * std::max(1.0, best);
  std::size_t ej = bj, ek = bk;
  while (ej + 1 < bk && score3(ej + 1, bk) >= best - tol) ++ej;
  while (ek + 1 < n && score3(bj, ek + 1) >= best - tol) ++ek;
  const double lo3 = inside(s.min + (s.max - s.min) * (0.5 * double(bj + ej)) / double(n));
  const double hi3 = inside(s.min + (s.max - s.min) * (0.5 * double(bk + ek)) / double(n));
  s.suggestions.push_back({"otsu3-low", lo3, below(lo3)});
  s.suggestions.push_back({"otsu3-high", hi3, below(hi3)});
  return s;
}

}  // namespace quadrix
