// XYZ, PTS, TXT point clouds: one point per line, "x y z" or "x y z nx ny nz" (the same count on
// every line), `#` comments; .pts may start with a point count that must then match.
#include <array>
#include <cmath>

#include <fmt/format.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/io/formats.h"
#include "core/io/text_reader.h"
#include "core/limits.h"
#include "core/log.h"

namespace quadrix::io {

PointCloud read_xyz(std::string_view text, const std::filesystem::path& path, bool count_line) {
  TextReader r(text, path);
  PointCloud cloud;
  std::size_t columns = 0, first_line = 0;
  long long declared = -1;
  // Normals all zero are placeholders (exporters write "0 0 0" for "none": CGAL's blobby.xyz):
  // the cloud is read without normals, which the fit then estimates. A zero normal among
  // non-zero ones, or the other way round, is refused at the first line that breaks the rule.
  std::size_t zero_normals = 0, zero_line = 0, normal_line = 0;
  std::array<double, 9> v{};
  while (r.next_line()) {
    std::size_t n = 0;
    for (std::string_view tok = r.token(); !tok.empty(); tok = r.token(), ++n) {
      double x = 0;
      if (!TextReader::parse(tok, x)) r.fail("'{}' is not a number", echo(tok));
      if (n < v.size()) v[n] = x;
    }
    if (n == 1 && count_line && columns == 0 && declared < 0 && v[0] >= 0 && v[0] == std::floor(v[0])) {
      // .pts: a leading point count; each point takes at least 6 bytes ("0 0 0\n").
      if (v[0] > static_cast<double>(text.size()) / 6)
        r.fail("the count line declares {:g} points, more than the file's {} bytes can hold", v[0], text.size());
      declared = static_cast<long long>(v[0]);
      continue;
    }
    if (n != 3 && n != 6 && n != 9) r.fail("{} values (expected 3: x y z, 6: x y z nx ny nz, or 9: x y z nx ny nz r g b)", n);
    if (columns == 0) {
      columns = n;
      first_line = r.line_number();
    } else if (n != columns) {
      r.fail("{} values but line {} has {} (all lines must have the same count)", n, first_line, columns);
    }
    const Eigen::Vector3d p(v[0], v[1], v[2]);
    if (!is_world_point(p)) r.fail("point ({} {} {}) {}", v[0], v[1], v[2], world_fault(p));
    cloud.points.push_back(p);
    if (n >= 6) {
      const Eigen::Vector3d nn(v[3], v[4], v[5]);
      if (!nn.allFinite()) r.fail("normal ({} {} {}) is not finite", v[3], v[4], v[5]);
      if (!(nn.norm() > 0)) {
        if (normal_line != 0)
          r.fail("zero normal (line {} has a non-zero one: either every normal is given, or all are 0 0 0 for none)",
                 normal_line);
        if (zero_normals++ == 0) zero_line = r.line_number();
      } else {
        if (zero_normals != 0)
          r.fail("normal ({} {} {}) after line {}'s zero normal (either every normal is given, or all are 0 0 0 for none)",
                 v[3], v[4], v[5], zero_line);
        if (normal_line == 0) normal_line = r.line_number();
        cloud.normals.push_back(nn.normalized());
      }
    }
    if (n == 9) {
      std::array<std::uint8_t, 3> c{};
      for (int k = 0; k < 3; ++k) {
        const double x = v[6 + k];
        if (!(x >= 0 && x <= 255 && x == std::floor(x))) r.fail("colour value {} is not an integer in 0..255", x);
        c[k] = static_cast<std::uint8_t>(x);
      }
      cloud.colours.push_back(c);
    }
  }
  if (zero_normals > 0)
    log::warn("{}: every normal is 0 0 0: read as points without normals", path.string());
  if (declared >= 0 && static_cast<std::size_t>(declared) != cloud.points.size())
    throw FormatError(fmt::format("{}: the count line declares {} points but the file holds {}", path.string(),
                                  declared, cloud.points.size()));
  return cloud;
}

void write_xyz(const PointCloud& cloud, const std::filesystem::path& path) {
  if (cloud.has_normals() && cloud.normals.size() != cloud.points.size())
    throw InvalidInput(
        fmt::format("{}: {} normals for {} points", path.string(), cloud.normals.size(), cloud.points.size()));
  if (cloud.has_colours() && (cloud.colours.size() != cloud.points.size() || !cloud.has_normals()))
    throw InvalidInput(fmt::format("{}: {} colours for {} points{} (XYZ holds colours after normals)", path.string(),
                                   cloud.colours.size(), cloud.points.size(), cloud.has_normals() ? "" : " without normals"));
  fmt::memory_buffer buf;
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    const auto& p = cloud.points[i];
    if (cloud.has_normals()) {
      const auto& n = cloud.normals[i];
      fmt::format_to(std::back_inserter(buf), "{:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g}", p.x(), p.y(), p.z(),
                     n.x(), n.y(), n.z());
      if (cloud.has_colours()) fmt::format_to(std::back_inserter(buf), " {} {} {}", cloud.colours[i][0], cloud.colours[i][1], cloud.colours[i][2]);
      buf.push_back('\n');
    } else {
      fmt::format_to(std::back_inserter(buf), "{:.17g} {:.17g} {:.17g}\n", p.x(), p.y(), p.z());
    }
  }
  write_file_atomically(path,
                        [&](std::ostream& os) { os.write(buf.data(), static_cast<std::streamsize>(buf.size())); });
}

}  // namespace quadrix::io
