#include "core/points_io.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <string>
#include <string_view>

#include <fmt/format.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/ply.h"

namespace quadrix {
namespace {

std::string lower_extension(const std::filesystem::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(fmt::format("{}: cannot open for reading", path.string()));
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw IoError(fmt::format("{}: read failed", path.string()));
  return bytes;
}

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// Line-by-line walk over a text buffer with 1-based line numbers and blank trimming.
class LineReader {
public:
  LineReader(std::string_view text, const std::filesystem::path& path) : s_(text), path_(path.string()) {}
  /// Next line (trimmed); false at the end.
  bool next(std::string_view& line) {
    if (pos_ >= s_.size()) return false;
    std::size_t eol = s_.find('\n', pos_);
    if (eol == std::string_view::npos) eol = s_.size();
    line = s_.substr(pos_, eol - pos_);
    pos_ = eol + 1;
    ++line_no_;
    while (!line.empty() && is_blank(line.front())) line.remove_prefix(1);
    while (!line.empty() && is_blank(line.back())) line.remove_suffix(1);
    return true;
  }
  /// Next line that is neither blank nor a `#` comment.
  bool next_data(std::string_view& line) {
    while (next(line))
      if (!line.empty() && line.front() != '#') return true;
    return false;
  }
  std::size_t line_no() const { return line_no_; }
  std::size_t bytes_left() const { return pos_ >= s_.size() ? 0 : s_.size() - pos_; }
  [[noreturn]] void fail(std::string_view what) const {
    throw FormatError(fmt::format("{}: line {}: {}", path_, line_no_, what));
  }
  /// Parses up to max numbers from a line's blank-separated tokens into out; returns the count.
  template <std::size_t N>
  std::size_t numbers(std::string_view line, std::array<double, N>& out) const {
    std::size_t n = 0, i = 0;
    while (i < line.size()) {
      while (i < line.size() && is_blank(line[i])) ++i;
      if (i >= line.size()) break;
      std::size_t j = i;
      while (j < line.size() && !is_blank(line[j])) ++j;
      std::string_view tok = line.substr(i, j - i);
      if (tok.front() == '#') break;  // trailing comment
      std::string_view num = tok.front() == '+' ? tok.substr(1) : tok;
      double v = 0;
      const auto [end, ec] = std::from_chars(num.data(), num.data() + num.size(), v);
      if (ec != std::errc() || end != num.data() + num.size() || num.empty())
        fail(fmt::format("'{}' is not a number", tok));
      if (n < N) out[n] = v;
      ++n;
      i = j;
    }
    return n;
  }

private:
  std::string_view s_;
  std::string path_;
  std::size_t pos_ = 0;
  std::size_t line_no_ = 0;
};

Eigen::Vector3d finite_point(const LineReader& r, const double* v, std::string_view what) {
  const Eigen::Vector3d p(v[0], v[1], v[2]);
  if (!p.allFinite()) r.fail(fmt::format("{} ({} {} {}) is not finite", what, v[0], v[1], v[2]));
  return p;
}

Eigen::Vector3d unit_normal(const LineReader& r, const double* v) {
  const Eigen::Vector3d n = finite_point(r, v, "normal");
  const double len = n.norm();
  if (!(len > 0)) r.fail("zero normal");
  return n / len;
}

void finish(PointCloud& cloud, const std::filesystem::path& path) {
  if (cloud.points.empty()) throw FormatError(fmt::format("{}: no points", path.string()));
}

PointCloud read_xyz(const std::filesystem::path& path, bool allow_count_line) {
  const std::string text = read_bytes(path);
  LineReader r(text, path);
  PointCloud cloud;
  cloud.points.reserve(static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')) + 1);
  std::string_view line;
  std::size_t columns = 0, first_line = 0;
  std::int64_t declared = -1;
  std::array<double, 8> v{};
  while (r.next_data(line)) {
    const std::size_t n = r.numbers(line, v);
    if (n == 1 && allow_count_line && columns == 0 && declared < 0 && v[0] >= 0 && v[0] == std::floor(v[0])) {
      declared = static_cast<std::int64_t>(v[0]);  // .pts: a leading point count
      continue;
    }
    if (n != 3 && n != 6) r.fail(fmt::format("{} values (expected 3: x y z, or 6: x y z nx ny nz)", n));
    if (columns == 0) {
      columns = n;
      first_line = r.line_no();
    } else if (n != columns) {
      r.fail(fmt::format("{} values but line {} has {} (all lines must have the same count)", n, first_line, columns));
    }
    cloud.points.push_back(finite_point(r, v.data(), "point"));
    if (n == 6) cloud.normals.push_back(unit_normal(r, v.data() + 3));
  }
  if (declared >= 0 && static_cast<std::size_t>(declared) != cloud.points.size())
    throw FormatError(fmt::format("{}: the count line declares {} points but the file holds {}", path.string(),
                                  declared, cloud.points.size()));
  finish(cloud, path);
  return cloud;
}

PointCloud read_off(const std::filesystem::path& path) {
  const std::string text = read_bytes(path);
  LineReader r(text, path);
  std::string_view line;
  if (!r.next_data(line)) throw FormatError(fmt::format("{}: no points (empty file)", path.string()));
  // Keyword: [ST][C][N][4][n]OFF; we support OFF, NOFF, COFF, NCOFF/CNOFF.
  std::size_t kw_end = 0;
  while (kw_end < line.size() && !is_blank(line[kw_end])) ++kw_end;
  const std::string_view kw = line.substr(0, kw_end);
  if (!kw.ends_with("OFF") || kw.size() > 5 || kw.find_first_not_of("CNOF") != std::string_view::npos)
    r.fail(fmt::format("'{}' is not an OFF keyword (OFF, NOFF, COFF, NCOFF)", kw));
  const bool normals = kw.substr(0, kw.size() - 3).find('N') != std::string_view::npos;
  // Counts: on the rest of the keyword line or on the next data line.
  std::array<double, 8> v{};
  std::size_t n = r.numbers(line.substr(kw_end), v);
  if (n == 0) {
    if (!r.next_data(line)) r.fail("missing the vertex/face/edge counts");
    n = r.numbers(line, v);
  }
  if (n < 2 || n > 3) r.fail(fmt::format("expected the counts 'vertices faces [edges]', found {} values", n));
  for (std::size_t i = 0; i < n; ++i)
    if (v[i] < 0 || v[i] != std::floor(v[i])) r.fail(fmt::format("count {} is not a non-negative integer", v[i]));
  const double nv = v[0], nf = v[1];
  // Validate before allocating: every vertex line holds at least "0 0 0\n".
  if (nv > static_cast<double>(r.bytes_left() / 6 + 1))
    r.fail(fmt::format("{} vertices declared but only {} bytes follow", nv, r.bytes_left()));
  const std::size_t count = static_cast<std::size_t>(nv);
  const std::size_t need = normals ? 6 : 3;
  PointCloud cloud;
  cloud.points.reserve(count);
  if (normals) cloud.normals.reserve(count);
  std::array<double, 16> row{};
  for (std::size_t i = 0; i < count; ++i) {
    if (!r.next_data(line)) r.fail(fmt::format("truncated: {} vertices declared, file ends after {}", count, i));
    const std::size_t m = r.numbers(line, row);
    if (m < need) r.fail(fmt::format("vertex {} has {} values, at least {} expected", i, m, need));
    cloud.points.push_back(finite_point(r, row.data(), "vertex"));
    if (normals) cloud.normals.push_back(unit_normal(r, row.data() + 3));
  }
  std::size_t face_lines = 0;
  while (face_lines < static_cast<std::size_t>(std::min(nf, 1e18)) && r.next_data(line)) ++face_lines;
  if (static_cast<double>(face_lines) < nf)
    throw FormatError(
        fmt::format("{}: {} faces declared but only {} face lines follow the vertices", path.string(), nf, face_lines));
  finish(cloud, path);
  return cloud;
}

PointCloud read_obj(const std::filesystem::path& path) {
  const std::string text = read_bytes(path);
  LineReader r(text, path);
  PointCloud cloud;
  std::vector<Eigen::Vector3d> normals;
  std::string_view line;
  std::array<double, 8> v{};
  while (r.next_data(line)) {
    const bool is_v = line.starts_with("v ") || line.starts_with("v\t");
    const bool is_vn = line.starts_with("vn ") || line.starts_with("vn\t");
    if (!is_v && !is_vn) continue;
    const std::size_t n = r.numbers(line.substr(is_v ? 1 : 2), v);
    if (n < 3) r.fail(fmt::format("{} values after '{}', at least 3 expected", n, is_v ? "v" : "vn"));
    if (is_v)
      cloud.points.push_back(finite_point(r, v.data(), "vertex"));
    else
      normals.push_back(unit_normal(r, v.data()));
  }
  if (!normals.empty() && normals.size() == cloud.points.size()) cloud.normals = std::move(normals);
  finish(cloud, path);
  return cloud;
}

PointCloud read_ply_points(const std::filesystem::path& path) {
  const ply::File f = ply::File::open(path);
  const ply::Element* e = f.header().find("vertex");
  if (!e) throw FormatError(f.message({}, -1, {}, ply::kNoByte, "no element 'vertex' in the header"));
  std::vector<std::string> props = {"x", "y", "z"};
  const int normal_count = (e->find("nx") >= 0) + (e->find("ny") >= 0) + (e->find("nz") >= 0);
  if (normal_count != 0 && normal_count != 3)
    throw FormatError(
        f.message("vertex", -1, {}, ply::kNoByte, "has some but not all of the normal properties nx ny nz"));
  if (normal_count == 3) props.insert(props.end(), {"nx", "ny", "nz"});
  const std::vector<ply::Request> req = {{"vertex", props}};
  const ply::Table t = f.read(req).front();
  PointCloud cloud;
  cloud.points.resize(t.rows);
  if (normal_count == 3) cloud.normals.resize(t.rows);
  for (std::size_t i = 0; i < t.rows; ++i) {
    for (std::size_t c = 0; c < props.size(); ++c)
      if (!std::isfinite(t(i, c)))
        throw FormatError(f.message("vertex", static_cast<std::int64_t>(i), props[c], t.byte_offset(i, c),
                                    fmt::format("value {} is not finite", t(i, c))));
    cloud.points[i] = {t(i, 0), t(i, 1), t(i, 2)};
    if (normal_count == 3) {
      const Eigen::Vector3d n(t(i, 3), t(i, 4), t(i, 5));
      const double len = n.norm();
      if (!(len > 0))
        throw FormatError(f.message("vertex", static_cast<std::int64_t>(i), "nx", t.byte_offset(i, 3), "zero normal"));
      cloud.normals[i] = n / len;
    }
  }
  finish(cloud, path);
  return cloud;
}

}  // namespace

PointCloud read_points(const std::filesystem::path& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".ply") return read_ply_points(path);
  if (ext == ".xyz" || ext == ".txt") return read_xyz(path, false);
  if (ext == ".pts") return read_xyz(path, true);
  if (ext == ".off") return read_off(path);
  if (ext == ".obj") return read_obj(path);
  // Unknown extension: sniff the first bytes.
  std::string head;
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(fmt::format("{}: cannot open for reading", path.string()));
    head.resize(16);
    in.read(head.data(), 16);
    head.resize(static_cast<std::size_t>(in.gcount()));
  }
  if (head.starts_with("ply")) return read_ply_points(path);
  if (head.starts_with("OFF") || head.starts_with("NOFF") || head.starts_with("COFF")) return read_off(path);
  return read_xyz(path, false);
}

void write_points_xyz(const PointCloud& cloud, const std::filesystem::path& path) {
  if (cloud.has_normals() && cloud.normals.size() != cloud.points.size())
    throw InvalidInput(
        fmt::format("{}: {} normals for {} points", path.string(), cloud.normals.size(), cloud.points.size()));
  fmt::memory_buffer buf;
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    const auto& p = cloud.points[i];
    if (cloud.has_normals()) {
      const auto& n = cloud.normals[i];
      fmt::format_to(std::back_inserter(buf), "{:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g}\n", p.x(), p.y(), p.z(),
                     n.x(), n.y(), n.z());
    } else {
      fmt::format_to(std::back_inserter(buf), "{:.17g} {:.17g} {:.17g}\n", p.x(), p.y(), p.z());
    }
  }
  write_file_atomically(path,
                        [&](std::ostream& os) { os.write(buf.data(), static_cast<std::streamsize>(buf.size())); });
}

}  // namespace quadrix
