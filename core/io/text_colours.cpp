#include "core/io/text_colours.h"

#include <algorithm>
#include <cmath>

#include "core/log.h"

namespace quadrix::io {

std::optional<TextColour> read_text_colour(TextReader& r, int most) {
  TextColour c;
  int n = 0;
  for (; n < most && !r.at_line_end(); ++n) {
    const std::string_view tok = r.token();
    double v = 0;
    if (!TextReader::parse(tok, v) || !std::isfinite(v)) c.numbers = false;
    c.decimal = c.decimal || tok.find_first_of(".eE") != std::string_view::npos;
    if (n < 3) c.value[n] = v;
  }
  if (n < 3) return std::nullopt;
  return c;
}

std::vector<std::array<std::uint8_t, 3>> text_colours_rgb8(std::span<const std::optional<TextColour>> colours,
                                                           std::size_t vertices, const std::filesystem::path& path) {
  if (colours.size() != vertices || vertices == 0 ||
      std::any_of(colours.begin(), colours.end(), [](const auto& c) { return !c.has_value(); }))
    return {};
  double most = 0;
  for (std::size_t v = 0; v < colours.size(); ++v) {
    const TextColour& c = *colours[v];
    const bool bad = !c.numbers || std::any_of(c.value.begin(), c.value.end(), [](double x) { return !(x >= 0 && x <= 255); });
    if (bad) {
      if (c.numbers)
        log::warn("{}: vertex {}: colour ({}, {}, {}) outside 0..255: the file's colours are left out", path.string(), v,
                  c.value[0], c.value[1], c.value[2]);
      else
        log::warn("{}: vertex {}: its colour is not three numbers: the file's colours are left out", path.string(), v);
      return {};
    }
    most = std::max({most, c.value[0], c.value[1], c.value[2]});
  }
  std::vector<std::array<std::uint8_t, 3>> out;
  out.reserve(vertices);
  for (const auto& c : colours) {
    const bool fractions = most <= 1 || (c->decimal && std::max({c->value[0], c->value[1], c->value[2]}) <= 1);
    std::array<std::uint8_t, 3> rgb{};
    for (int k = 0; k < 3; ++k) rgb[k] = static_cast<std::uint8_t>(std::lround(fractions ? 255 * c->value[k] : c->value[k]));
    out.push_back(rgb);
  }
  return out;
}

}  // namespace quadrix::io
