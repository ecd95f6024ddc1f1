// Volume statistics and Otsu's thresholds (convert/volume_stats.h) against hand-computed answers.
#include <gtest/gtest.h>

#include <random>

#include "convert/volume_stats.h"
#include "core/error.h"

using namespace quadrix;

namespace {
Volume volume_of(std::vector<float> values) {
  Volume v;
  v.dims = {int(values.size()), 1, 1};
  v.values = std::move(values);
  return v;
}
}  // namespace

TEST(VolumeStats, OtsuOnTwoSeparatedClassesIsTheMiddleOfTheGap) {
  // Classes in bins 0 and 5 of 6 on [0, 6]: every boundary 1..5 gives the same split; the middle is 3.
  EXPECT_DOUBLE_EQ(otsu_threshold({5, 0, 0, 0, 0, 5}, 0.0, 6.0), 3.0);
  // Unequal classes with mass in between: brute force over the boundaries.
  const std::vector<std::size_t> h = {10, 30, 5, 1, 2, 20, 8, 1};
  double best = -1, arg = 0;
  for (std::size_t k = 1; k < h.size(); ++k) {
    double w0 = 0, w1 = 0, s0 = 0, s1 = 0;
    for (std::size_t b = 0; b < h.size(); ++b) (b < k ? w0 : w1) += h[b], (b < k ? s0 : s1) += h[b] * (b + 0.5);
    const double m0 = s0 / w0, m1 = s1 / w1, var = w0 * w1 * (m0 - m1) * (m0 - m1);
    if (var > best) best = var, arg = double(k);
  }
  EXPECT_DOUBLE_EQ(otsu_threshold(h, 0.0, 8.0), arg);
}

TEST(VolumeStats, SummaryOfAKnownSample) {
  std::vector<float> v;
  for (int i = 1; i <= 100; ++i) v.push_back(float(i));
  const VolumeStats s = volume_stats(volume_of(v));
  EXPECT_EQ(s.samples, 100u);
  EXPECT_EQ(s.min, 1);
  EXPECT_EQ(s.max, 100);
  EXPECT_DOUBLE_EQ(s.mean, 50.5);
  for (const auto& [p, value] : s.percentiles) EXPECT_EQ(value, std::max(1.0, std::ceil(p))) << p;  // nearest rank
  std::size_t total = 0;
  for (auto c : s.histogram) total += c;
  EXPECT_EQ(total, 100u);
  ASSERT_EQ(s.suggestions.size(), 3u);
  // Uniform data: Otsu halves the range.
  EXPECT_NEAR(s.suggestions[0].value, 50.5, 99.0 / 256);
  EXPECT_LT(s.suggestions[1].value, s.suggestions[2].value);
}

TEST(VolumeStats, ThreeLevelsGiveBothGaps) {
  std::vector<float> v;
  std::mt19937 rng(1);
  std::normal_distribution<float> noise(0, 1);
  for (int i = 0; i < 3000; ++i) v.push_back(i % 3 == 0 ? 0 + noise(rng) : i % 3 == 1 ? 100 + noise(rng) : 300 + noise(rng));
  const VolumeStats s = volume_stats(volume_of(v));
  EXPECT_GT(s.suggestions[1].value, 5);
  EXPECT_LT(s.suggestions[1].value, 95);
  EXPECT_GT(s.suggestions[2].value, 105);
  EXPECT_LT(s.suggestions[2].value, 295);
  EXPECT_NEAR(s.suggestions[1].below, 1.0 / 3, 1e-9);
  EXPECT_NEAR(s.suggestions[2].below, 2.0 / 3, 1e-9);
}

TEST(VolumeStats, ConstantDataHasNoSuggestionAndBadDataThrows) {
  EXPECT_TRUE(volume_stats(volume_of({3, 3, 3})).suggestions.empty());
  EXPECT_THROW(volume_stats(volume_of({})), InvalidInput);
  EXPECT_THROW(volume_stats(volume_of({1, std::numeric_limits<float>::quiet_NaN()})), InvalidInput);
}
