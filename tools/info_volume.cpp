#include "tools/info_volume.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <iostream>

#include <fmt/format.h>

#include "convert/volume_stats.h"

namespace quadrix::cli {
namespace {

std::string lower(std::string s) {
  for (auto& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// "A,B,C": three numbers within range. \throws CLI::ValidationError naming the option.
std::array<double, 3> triple(const std::string& text, const char* option, NumberRange range, bool integral) {
  std::array<double, 3> v{};
  std::size_t start = 0;
  for (int a = 0; a < 3; ++a) {
    const std::size_t comma = text.find(',', start);
    if ((comma == std::string::npos) != (a == 2))
      throw CLI::ValidationError(option, fmt::format("expected three comma-separated numbers, got '{}'", text.substr(0, 80)));
    std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (const std::string why = number(range)(item); !why.empty())
      throw CLI::ValidationError(option, fmt::format("'{}': {}", text.substr(0, 80), why));
    v[a] = std::stod(item);
    if (integral && v[a] != std::floor(v[a]))
      throw CLI::ValidationError(option, fmt::format("'{}': {} is not an integer", text.substr(0, 80), item));
    start = comma + 1;
  }
  return v;
}

}  // namespace

bool is_volume_file(const std::string& path, const RawVolumeArgs& raw) {
  if (!raw.dims.empty() || !raw.type.empty()) return true;
  const std::string p = lower(path);
  for (const char* ext : {".nhdr", ".nrrd", ".inr", ".inr.gz"})
    if (p.ends_with(ext)) return true;
  return false;
}

std::optional<RawVolumeLayout> raw_layout(const RawVolumeArgs& raw) {
  if (raw.dims.empty() && raw.type.empty()) {
    if (!raw.spacing.empty() || raw.big_endian || raw.header_bytes)
      throw CLI::ValidationError("--dims", "--spacing, --big-endian and --header-bytes are for raw volumes (with --dims and --type)");
    return std::nullopt;
  }
  if (raw.dims.empty() || raw.type.empty()) throw CLI::ValidationError("--dims", "raw volumes need both --dims and --type");
  RawVolumeLayout l;
  const auto d = triple(raw.dims, "--dims", {.lo = 1, .hi = 1 << 30}, true);
  l.dims = {int(d[0]), int(d[1]), int(d[2])};
  try {
    l.type = parse_voxel_type(raw.type);
  } catch (const std::exception& e) {
    throw CLI::ValidationError("--type", e.what());
  }
  l.big_endian = raw.big_endian;
  l.header_bytes = raw.header_bytes;
  if (!raw.spacing.empty()) {
    const auto s = triple(raw.spacing, "--spacing", {.lo = 0, .open_lo = true}, false);
    l.spacing = Eigen::Vector3d(s[0], s[1], s[2]);
  }
  return l;
}

ExitCode run_info_volume(const std::string& path, const RawVolumeArgs& raw, bool as_json, Report& report) {
  const Volume v = read_volume(path, raw_layout(raw));
  const VolumeStats s = volume_stats(v);
  nlohmann::json j;
  j["file"] = path;
  j["kind"] = "volume";
  j["valid"] = true;
  j["dims"] = v.dims;
  j["type"] = v.voxel_type;
  j["spacing"] = {v.spacing.x(), v.spacing.y(), v.spacing.z()};
  j["origin"] = {v.origin.x(), v.origin.y(), v.origin.z()};
  j["samples"] = s.samples;
  j["min"] = s.min;
  j["max"] = s.max;
  j["mean"] = s.mean;
  j["stddev"] = s.stddev;
  nlohmann::json pc = nlohmann::json::object();
  for (const auto& [p, value] : s.percentiles) pc[fmt::format("{:g}", p)] = value;
  j["percentiles"] = pc;
  std::vector<double> edges;
  for (std::size_t b = 0; b <= s.histogram.size(); ++b)
    edges.push_back(s.min + (s.max - s.min) * double(b) / double(s.histogram.size()));
  j["histogram"] = {{"edges", edges}, {"counts", s.histogram}};
  nlohmann::json sj = nlohmann::json::array();
  for (const auto& g : s.suggestions) sj.push_back({{"method", g.method}, {"iso", g.value}, {"fraction_below", g.below}});
  j["suggested_iso"] = sj;
  report.json["info"] = j;
  if (as_json) {
    std::cout << j.dump(2) << "\n";
    return kOk;
  }
  std::cout << fmt::format("{}: volume {}x{}x{} {}, spacing {:g} {:g} {:g}, {} samples\n", path, v.dims[0], v.dims[1],
                           v.dims[2], v.voxel_type, v.spacing.x(), v.spacing.y(), v.spacing.z(), s.samples);
  std::cout << fmt::format("  range        {:.6g} – {:.6g}, mean {:.6g}, stddev {:.6g}\n", s.min, s.max, s.mean, s.stddev);
  std::cout << "  percentiles ";
  for (const auto& [p, value] : s.percentiles) std::cout << fmt::format(" {:g}%: {:.6g}", p, value);
  std::cout << "\n";
  const std::size_t most = *std::max_element(s.histogram.begin(), s.histogram.end());
  // A constant volume: one value, not a column of bins all from it to itself.
  if (s.min == s.max)
    std::cout << fmt::format("  histogram    every sample is {:.6g}\n", s.min);
  else
    std::cout << fmt::format("  histogram    {} bins, bar length ∝ log(1 + count)\n", s.histogram.size());
  for (std::size_t b = 0; b < s.histogram.size() && s.min != s.max; ++b) {
    const int bar = most ? int(std::lround(40.0 * std::log1p(double(s.histogram[b])) / std::log1p(double(most)))) : 0;
    std::cout << fmt::format("    {:>11.5g} – {:<11.5g}{:>12} {}\n", edges[b], edges[b + 1], s.histogram[b],
                             std::string(std::size_t(bar), '#'));
  }
  if (s.suggestions.empty()) {
    std::cout << "  suggested iso none: the volume is constant\n";
    return kOk;
  }
  std::cout << "  suggested iso\n";
  for (const auto& g : s.suggestions)
    std::cout << fmt::format("    {:<11} {:<12.6g} ({:.1f} % of the samples below)\n", g.method, g.value, 100.0 * g.below);
  std::cout << fmt::format("  e.g. quadrix convert volume {} --iso {:.6g} -o iso.qxm\n", path, s.suggestions[0].value);
  return kOk;
}

}  // namespace quadrix::cli
