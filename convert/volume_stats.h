#pragma once
/// What a volume holds and which iso-values suit it: value range, percentiles, a histogram, and
/// thresholds from Otsu's method (Otsu 1979: the threshold that maximises the between-class
/// variance of the histogram; with two thresholds, three classes, e.g. background, soft
/// tissue, bone).
#include <cstddef>
#include <string>
#include <vector>

#include "convert/volume.h"

namespace quadrix {

struct VolumeStatsOptions {
  int otsu_bins = 256;       ///< histogram bins over [min, max] for Otsu's thresholds
  int histogram_bins = 16;   ///< bins of the coarse histogram (VolumeStats::histogram)
  /// Percentiles to report, in [0, 100].
  std::vector<double> percentiles = {1, 5, 25, 50, 75, 95, 99};
};

/// One suggested iso-value.
struct IsoSuggestion {
  std::string method;  ///< "otsu" (two classes), "otsu3-low", "otsu3-high" (three classes)
  double value = 0;    ///< strictly inside (min, max)
  double below = 0;    ///< fraction of the samples below the value
};

struct VolumeStats {
  std::size_t samples = 0;
  double min = 0, max = 0, mean = 0, stddev = 0;
  std::vector<std::pair<double, double>> percentiles;  ///< (percent, value): nearest-rank over all samples
  /// Coarse histogram: histogram_bins equal bins over [min, max] (the last one closed).
  std::vector<std::size_t> histogram;
  /// Best first: Otsu's two-class threshold, then the three-class pair. Empty for constant data.
  std::vector<IsoSuggestion> suggestions;
};

/// Otsu's threshold over a histogram of `bins` equal bins on [lo, hi]: the bin boundary that
/// maximises the between-class variance; when several boundaries tie (an empty stretch between
/// two classes) the middle of the tied stretch. Returns lo for an empty or one-bin histogram.
double otsu_threshold(const std::vector<std::size_t>& histogram, double lo, double hi);

/// Statistics of volume's samples. \throws InvalidInput for an empty volume, non-finite samples
/// or bad options.
VolumeStats volume_stats(const Volume& volume, const VolumeStatsOptions& options = {});

}  // namespace quadrix
