#include "convert/ellipsoids_csv.h"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>

#include <fmt/format.h>

#include "core/error.h"
#include "core/limits.h"
#include "core/io/file.h"
#include "core/io/text_reader.h"

namespace quadrix {

Model read_ellipsoids_csv(const std::filesystem::path& path) {
  const std::string raw = io::read_file(path);
  // An empty cell (",,", a comma at either end of a line) would shift the columns after it once
  // commas read as blanks: refused where it is (a comment's commas aside).
  {
    std::size_t line = 1, col = 1;
    bool in_comment = false, cell_empty = true, line_has_comma = false;
    const auto refuse = [&] {
      throw FormatError(fmt::format("{}:{}:{}: empty cell (a value missing between commas)", path.string(), line, col));
    };
    for (const char c : raw) {
      if (c == '\n') {
        if (line_has_comma && cell_empty) refuse();
        ++line, col = 1, in_comment = false, cell_empty = true, line_has_comma = false;
        continue;
      }
      if (c == '#') in_comment = true;
      if (!in_comment) {
        if (c == ',') {
          if (cell_empty) refuse();
          cell_empty = true, line_has_comma = true;
        } else if (c != ' ' && c != '\t' && c != '\r') {
          cell_empty = false;
        }
      }
      ++col;
    }
    if (line_has_comma && cell_empty) refuse();
  }
  std::string text = raw;
  std::replace(text.begin(), text.end(), ',', ' ');  // commas as blanks: columns keep their place
  io::TextReader in(text, path);
  Model m;
  bool first = true;
  while (in.next_line()) {
    std::string_view tok = in.token();
    double v = 0;
    if (first) {
      first = false;
      // A header row names the columns: not one of its cells is a number (a data row with a typo,
      // "O,0,0,…", is a data row and its bad cell is refused below).
      bool any_number = false;
      for (std::string_view t = tok; !t.empty(); t = in.token()) any_number = any_number || io::TextReader::parse(t, v);
      if (!any_number) continue;
      in = io::TextReader(text, path);  // read the row again as data
      in.next_line();
      tok = in.token();
    }
    double x[15];
    int count = 0;
    const std::size_t row = m.glyphs.size() + 1;  // the ellipsoids counted from 1
    for (; !tok.empty() && count < 15; tok = in.token(), ++count) {
      if (!io::TextReader::parse(tok, x[count]) || !std::isfinite(x[count]))
        in.fail("ellipsoid {} value {}: '{}' is not a finite number", row, count + 1, io::echo(tok));
    }
    if (!tok.empty()) in.fail("ellipsoid {}: more than 15 values", row);
    if (count != 12 && count != 15)
      in.fail("ellipsoid {}: {} values; expected 12 (centre, three axes) or 15 (and r, g, b)", row, count);
    Glyph g;
    g.kind = GlyphKind::ellipsoid;
    g.centre = {x[0], x[1], x[2]};
    for (int k = 0; k < 3; ++k) g.axes.col(k) = Eigen::Vector3d(x[3 + 3 * k], x[4 + 3 * k], x[5 + 3 * k]);
    // Beyond the world limit the model could not be written (core/limits.h): refuse the row here.
    if (!is_world_point(g.centre))
      in.fail("ellipsoid {}: centre ({:g}, {:g}, {:g}) {}", row, x[0], x[1], x[2], world_fault(g.centre));
    for (int k = 0; k < 3; ++k)
      if (!is_world_point(g.axes.col(k)))
        in.fail("ellipsoid {}: axis {} ({:g}, {:g}, {:g}) {}", row, k + 1, x[3 + 3 * k], x[4 + 3 * k], x[5 + 3 * k],
                world_fault(Eigen::Vector3d(g.axes.col(k))));
    if (!(std::abs(g.axes.determinant()) > 0)) in.fail("ellipsoid {}: its axes are singular (no volume)", row);
    if (count == 15) {
      Rgb c;
      for (int k = 0; k < 3; ++k) {
        if (!(x[12 + k] >= 0 && x[12 + k] <= 255 && x[12 + k] == std::floor(x[12 + k])))
          in.fail("ellipsoid {}: colour {} is not an integer in 0..255", row, x[12 + k]);
        c[k] = static_cast<std::uint8_t>(x[12 + k]);
      }
      g.colour = c;
    }
    m.glyphs.push_back(g);
  }
  if (m.glyphs.empty()) throw FormatError(path.string() + ": no ellipsoids");
  return m;
}

}  // namespace quadrix
