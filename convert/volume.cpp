// Volume readers (NRRD, INRIMAGE-4, raw), the Marschner–Lobb function, and the quadratic
// iso-surface conversion ([Stoll06] §5.1.2).
#include "convert/volume.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>

#include <Eigen/LU>
#include <Eigen/QR>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <zlib.h>

#include "convert/tetmesh_io.h"
#include "core/atomic_file.h"
#include "core/bounds.h"
#include "core/error.h"
#include "core/io/file.h"
#include "core/io/text_reader.h"
#include "core/limits.h"
#include "core/log.h"

namespace quadrix {
namespace {

namespace fs = std::filesystem;
using Eigen::Matrix4d;
using Eigen::Vector3d;

// ---------------------------------------------------------------------------------------------
// Bytes and headers

// Samples along one axis, at most (decode() and the header checks); bytes a header may skip.
constexpr int kMaxVolumeSize = 1 << 16;
constexpr std::size_t kMaxVolumeSkip = std::size_t{1} << 30;

std::string lower(std::string_view s) {
  std::string out(s);
  for (auto& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string_view::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return std::string(s.substr(b, e - b + 1));
}

bool ends_with(const fs::path& p, std::string_view suffix) {
  const std::string name = lower(p.filename().string());
  return name.size() >= suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::size_t voxel_bytes(VoxelType t) {
  switch (t) {
    case VoxelType::uint8: case VoxelType::int8: return 1;
    case VoxelType::uint16: case VoxelType::int16: return 2;
    case VoxelType::uint32: case VoxelType::int32: case VoxelType::float32: return 4;
    case VoxelType::float64: return 8;
  }
  return 1;
}

const char* voxel_name(VoxelType t) {
  switch (t) {
    case VoxelType::uint8: return "uint8";
    case VoxelType::int8: return "int8";
    case VoxelType::uint16: return "uint16";
    case VoxelType::int16: return "int16";
    case VoxelType::uint32: return "uint32";
    case VoxelType::int32: return "int32";
    case VoxelType::float32: return "float";
    case VoxelType::float64: return "double";
  }
  return "?";
}

template <typename T>
T load(const char* p, bool swap) {
  std::array<char, sizeof(T)> b;
  std::memcpy(b.data(), p, sizeof(T));
  if (swap) std::reverse(b.begin(), b.end());
  T v;
  std::memcpy(&v, b.data(), sizeof(T));
  return v;
}

// Decodes dims-many voxels from data (exactly the right size: checked here) into a Volume.
Volume decode(std::string_view data, const std::array<int, 3>& dims, VoxelType type, bool big_endian,
              const Vector3d& spacing, const std::string& what) {
  for (int a = 0; a < 3; ++a)
    if (dims[a] < 1 || dims[a] > kMaxVolumeSize)
      throw FormatError(fmt::format("{}: size {} along axis {} is out of range [1, {}]", what, dims[a], a, kMaxVolumeSize));
  const std::size_t n = static_cast<std::size_t>(dims[0]) * dims[1] * dims[2];
  const std::size_t need = n * voxel_bytes(type);
  if (data.size() != need)
    throw FormatError(fmt::format("{}: header says {}x{}x{} {} = {} bytes of data, the file holds {}", what, dims[0],
                                  dims[1], dims[2], voxel_name(type), need, data.size()));
  for (int a = 0; a < 3; ++a)
    if (!(spacing[a] > 0) || !std::isfinite(spacing[a]))
      throw FormatError(fmt::format("{}: spacing {} along axis {} must be finite and > 0", what, spacing[a], a));
  Volume v;
  v.dims = dims;
  v.spacing = spacing;
  v.source = what;
  v.voxel_type = voxel_name(type);
  v.values.resize(n);
  const bool swap = big_endian != (std::endian::native == std::endian::big);
  const char* p = data.data();
  const std::size_t s = voxel_bytes(type);
  for (std::size_t i = 0; i < n; ++i, p += s) {
    double x = 0;
    switch (type) {
      case VoxelType::uint8: x = static_cast<std::uint8_t>(*p); break;
      case VoxelType::int8: x = static_cast<std::int8_t>(*p); break;
      case VoxelType::uint16: x = load<std::uint16_t>(p, swap); break;
      case VoxelType::int16: x = load<std::int16_t>(p, swap); break;
      case VoxelType::uint32: x = load<std::uint32_t>(p, swap); break;
      case VoxelType::int32: x = load<std::int32_t>(p, swap); break;
      case VoxelType::float32: x = load<float>(p, swap); break;
      case VoxelType::float64: x = load<double>(p, swap); break;
    }
    if (!std::isfinite(x))
      throw FormatError(fmt::format("{}: voxel {} (byte offset {} of the data) is not finite", what, i, i * s));
    v.values[i] = static_cast<float>(x);
  }
  return v;
}

// The grid's corners inside the world range (core/limits.h): a spacing of 1e308 is refused, not
// turned into infinite positions. \throws FormatError naming the volume.
void check_volume_extent(const Volume& v) {
  for (int a = 0; a < 3; ++a) {
    const double lo = v.origin[a], hi = v.origin[a] + v.spacing[a] * (v.dims[a] - 1);
    if (!is_world_value(lo) || !is_world_value(hi))
      throw FormatError(fmt::format("{}: along axis {} the grid spans [{:g}, {:g}] (spacing {:g}), beyond ±{:g}, the "
                                    "largest world coordinate Quadrix handles",
                                    v.source, a, lo, hi, v.spacing[a], kMaxWorldCoordinate));
  }
}

}  // namespace

std::pair<double, double> Volume::range() const {
  if (values.empty()) return {0.0, 0.0};
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  return {*lo, *hi};
}

VoxelType parse_voxel_type(std::string_view name) {
  const std::string t = lower(trim(name));
  if (t == "uint8" || t == "uchar" || t == "unsigned char" || t == "uint8_t") return VoxelType::uint8;
  if (t == "int8" || t == "signed char" || t == "int8_t") return VoxelType::int8;
  if (t == "uint16" || t == "ushort" || t == "unsigned short" || t == "unsigned short int" || t == "uint16_t")
    return VoxelType::uint16;
  if (t == "int16" || t == "short" || t == "short int" || t == "signed short" || t == "signed short int" ||
      t == "int16_t")
    return VoxelType::int16;
  if (t == "uint32" || t == "uint" || t == "unsigned int" || t == "uint32_t") return VoxelType::uint32;
  if (t == "int32" || t == "int" || t == "signed int" || t == "int32_t") return VoxelType::int32;
  if (t == "float" || t == "float32") return VoxelType::float32;
  if (t == "double" || t == "float64") return VoxelType::float64;
  throw InvalidInput(fmt::format("unknown voxel type '{}' (uint8, int8, uint16, int16, uint32, int32, float, double)",
                                 io::echo(name)));
}

Volume read_raw_volume(const fs::path& path, const RawVolumeLayout& layout) {
  const std::string what = path.string();
  // Read no more than the layout promises (a small .gz must not inflate past it).
  double need = static_cast<double>(voxel_bytes(layout.type));
  for (const int d : layout.dims) need *= std::max(d, 0);
  need += static_cast<double>(layout.header_bytes);
  const std::size_t bound = need > 1e18 ? io::kNoLimit : static_cast<std::size_t>(need);
  const io::ByteLimit limit{bound, "its --dims, --type and --header-bytes give"};
  const std::string bytes = ends_with(path, ".gz") ? io::read_gzip(path, limit) : io::read_file(path, limit);
  if (layout.header_bytes > bytes.size())
    throw FormatError(fmt::format("{}: header of {} bytes is longer than the file ({} bytes)", what,
                                  layout.header_bytes, bytes.size()));
  Volume v = decode(std::string_view(bytes).substr(layout.header_bytes), layout.dims, layout.type, layout.big_endian,
                    layout.spacing, what);
  check_volume_extent(v);
  return v;
}

namespace {

// Header values as the text reader's tokens, so a message points at the one at fault.
template <typename T>
T header_number(io::TextReader& in, std::string_view field) {
  const std::string_view tok = in.token();
  if (tok.empty()) in.fail("field '{}': a number is missing", field);
  if constexpr (std::is_floating_point_v<T>) {
    double v = 0;
    // NRRD writes NaN for "unknown" spacing; callers decide what to do with it.
    if (lower(tok) == "nan") return std::numeric_limits<T>::quiet_NaN();
    if (!io::TextReader::parse(tok, v)) in.fail("field '{}': '{}' is not a number", field, io::echo(tok));
    return static_cast<T>(v);
  } else {
    long long v = 0;
    if (!io::TextReader::parse(tok, v) || v < std::numeric_limits<T>::min() || v > std::numeric_limits<T>::max())
      in.fail("field '{}': '{}' is not an integer in [{}, {}]", field, io::echo(tok), std::numeric_limits<T>::min(),
              std::numeric_limits<T>::max());
    return static_cast<T>(v);
  }
}

// The numbers of the rest of the line, read through `(`, `)` and `,` ("(1,0,0) (0,1,0)").
std::vector<double> header_vectors(io::TextReader& in, std::string_view field) {
  std::vector<double> out;
  for (;;) {
    const std::string_view rest = in.rest_of_line();
    const std::size_t b = rest.find_first_not_of(" \t\r(),");
    if (b == std::string_view::npos || out.size() > 64) return out;
    in.take(b);
    const std::string_view tok = in.take(std::min(rest.find_first_of(" \t\r(),", b), rest.size()) - b);
    double v = 0;
    if (!io::TextReader::parse(tok, v)) in.fail("field '{}': '{}' is not a number", field, io::echo(tok));
    out.push_back(v);
  }
}

// Voxels along the axes of a header: each in [1, 65536] (the size decode() accepts), so the
// promised byte count never overflows. \throws FormatError naming the file.
std::size_t promised_bytes(const std::array<int, 3>& dims, VoxelType type, const std::string& what) {
  for (int a = 0; a < 3; ++a)
    if (dims[a] < 1 || dims[a] > kMaxVolumeSize)
      throw FormatError(fmt::format("{}: size {} along axis {} is out of range [1, {}]", what, dims[a], a,
                                    kMaxVolumeSize));
  return static_cast<std::size_t>(dims[0]) * dims[1] * dims[2] * voxel_bytes(type);
}

// The most compressed bytes a gzip stream of n bytes takes (stored blocks and a generous header).
std::size_t gzip_bound(std::size_t n) { return n + (n >> 3) + (n >> 6) + (std::size_t{1} << 16); }

}  // namespace

Volume read_nrrd(const fs::path& path) {
  const std::string what = path.string();
  // The header ends at the first empty line (attached data follows) or with the file (.nhdr).
  constexpr std::size_t kMaxHeader = std::size_t{1} << 20;
  const std::string head = io::read_file_prefix(path, kMaxHeader + 1);
  if (!head.starts_with("NRRD000"))
    throw FormatError(io::text_message(path, 1, 1, "not a NRRD file (no NRRD000x magic on line 1)"));
  std::size_t header_bytes = head.size(), data_start = std::string::npos;
  for (std::size_t b = 0; b < head.size();) {
    const std::size_t e = head.find('\n', b);
    if (e == std::string::npos) break;
    if (e == b || (e == b + 1 && head[b] == '\r')) {
      header_bytes = b;
      data_start = e + 1;
      break;
    }
    b = e + 1;
  }
  if (data_start == std::string::npos && head.size() > kMaxHeader)
    throw FormatError(fmt::format("{}: no end of the header (an empty line) in its first {} bytes", what, kMaxHeader));

  std::optional<VoxelType> type;
  int dimension = 0;
  std::vector<int> sizes;
  Vector3d spacing = Vector3d::Ones();
  Vector3d origin = Vector3d::Zero();
  std::string endian, encoding = "raw", data_file;
  long long byte_skip = 0;
  long long line_skip = 0;
  io::TextReader in(std::string_view(head).substr(0, header_bytes), path, '\0');
  in.next_line();  // the magic
  while (in.next_line()) {
    const std::string_view line = in.rest_of_line();
    if (line[0] == '#') continue;
    if (line.find(":=") != std::string_view::npos) continue;  // key/value pair
    const auto colon = line.find(": ");
    if (colon == std::string_view::npos) in.fail("expected 'field: value', got '{}'", io::echo(trim(line)));
    const std::string field = lower(trim(in.take(colon)));
    in.take(2);
    const std::string value = trim(in.rest_of_line());
    if (field == "type") {
      try {
        type = parse_voxel_type(value);
      } catch (const InvalidInput& err) {
        in.fail("{}", err.what());
      }
    } else if (field == "dimension") {
      dimension = header_number<int>(in, field);
    } else if (field == "sizes") {
      while (!in.at_line_end() && sizes.size() < 4) sizes.push_back(header_number<int>(in, field));
    } else if (field == "spacings") {
      for (int a = 0; a < 3; ++a) {
        const double s = header_number<double>(in, field);
        spacing[a] = std::isnan(s) ? 1.0 : std::abs(s);
      }
      if (!in.at_line_end()) in.fail("'spacings' needs 3 values, got '{}'", io::echo(value));
    } else if (field == "space directions") {
      // "(a,b,c) (d,e,f) (g,h,i)": the spacing is each vector's length (axis-aligned grids).
      const auto w = header_vectors(in, field);
      if (w.size() != 9) in.fail("'space directions' needs three 3-vectors, got '{}'", io::echo(value));
      for (int a = 0; a < 3; ++a) spacing[a] = Vector3d(w[3 * a], w[3 * a + 1], w[3 * a + 2]).norm();
    } else if (field == "space origin") {
      const auto w = header_vectors(in, field);
      if (w.size() != 3) in.fail("'space origin' needs 3 values, got '{}'", io::echo(value));
      origin = Vector3d(w[0], w[1], w[2]);
    } else if (field == "endian") {
      endian = lower(value);
      if (endian != "little" && endian != "big") in.fail("endian must be 'little' or 'big', got '{}'", io::echo(value));
    } else if (field == "encoding") {
      encoding = lower(value);
      if (encoding != "raw" && encoding != "gzip" && encoding != "gz")
        in.fail("encoding '{}' is not supported (raw, gzip)", io::echo(value));
    } else if (field == "data file" || field == "datafile") {
      data_file = value;
    } else if (field == "byte skip") {
      byte_skip = header_number<long long>(in, field);
      if (byte_skip < -1) in.fail("byte skip {} (−1 or ≥ 0)", byte_skip);
    } else if (field == "line skip") {
      line_skip = header_number<long long>(in, field);
      if (line_skip < 0) in.fail("line skip {} (≥ 0)", line_skip);
    }
  }
  if (!type) throw FormatError(fmt::format("{}: missing required field 'type'", what));
  if (dimension != 3) throw FormatError(fmt::format("{}: dimension {} (only 3-D scalar volumes are supported)", what, dimension));
  if (sizes.size() != 3)
    throw FormatError(fmt::format("{}: 'sizes' has {} entries, dimension is 3", what, sizes.size()));
  if (voxel_bytes(*type) > 1 && endian.empty())
    throw FormatError(fmt::format("{}: missing field 'endian' for {}-byte type {}", what, voxel_bytes(*type),
                                  voxel_name(*type)));
  const bool gz = encoding == "gzip" || encoding == "gz";
  if (gz && byte_skip == -1) throw FormatError(fmt::format("{}: 'byte skip: -1' needs raw encoding", what));
  const std::array<int, 3> dims{sizes[0], sizes[1], sizes[2]};
  const std::size_t need = promised_bytes(dims, *type, what);
  const std::size_t skip = byte_skip > 0 ? static_cast<std::size_t>(byte_skip) : 0;
  if (skip > kMaxVolumeSkip) throw FormatError(fmt::format("{}: byte skip {} is over {}", what, skip, kMaxVolumeSkip));
  // Raw data are exactly skip + need bytes; gzip data inflate to exactly that (NRRD skips bytes of
  // the decompressed data), checked as they arrive. Line skips and `byte skip: -1` read the file.
  const std::size_t bound = byte_skip == -1 || line_skip > 0 ? io::kNoLimit : skip + need;

  std::string data;
  std::string data_what = what;
  bool inflated = false;
  if (!data_file.empty()) {
    if (data_file.rfind("LIST", 0) == 0 || data_file.find_first_of(" \t") != std::string::npos)
      throw FormatError(fmt::format("{}: multi-file data ('data file: {}') is not supported", what, io::echo(data_file)));
    fs::path df = data_file;
    if (df.is_relative()) df = path.parent_path() / df;
    data_what = fmt::format("{} (data file {})", what, df.string());
    std::error_code ec;
    if (fs::exists(df, ec) && !fs::is_directory(df, ec) && !fs::is_regular_file(df, ec))
      throw FormatError(fmt::format("{}: 'data file: {}' is not a regular file (a device or a pipe)", what,
                                    io::echo(data_file)));
    try {
      if (gz && line_skip == 0) {
        data = io::read_gzip(df, {bound, io::kHeaderPromise});
        inflated = true;
      } else {
        data = io::read_file(df, {gz ? gzip_bound(need + skip) : bound, io::kHeaderPromise});
      }
    } catch (const IoError& e) {  // the header is where the user looks first: name it too
      throw IoError(fmt::format("{}: data file '{}': {}", what, io::echo(data_file), e.what()));
    } catch (const FormatError& e) {
      throw FormatError(fmt::format("{}: data file '{}': {}", what, io::echo(data_file), e.what()));
    }
  } else {
    if (data_start == std::string::npos)
      throw FormatError(fmt::format("{}: no 'data file' field and no attached data after an empty line", what));
    const std::size_t limit = gz ? gzip_bound(need + skip) : bound;
    data = io::read_file(path, {limit == io::kNoLimit ? limit : data_start + limit, io::kHeaderPromise})
               .substr(data_start);
  }
  std::string_view d = data;
  if (!inflated)
    for (long long l = 0; l < line_skip; ++l) {
      const auto nl = d.find('\n');
      if (nl == std::string_view::npos)
        throw FormatError(fmt::format("{}: 'line skip: {}' runs past the end of the data", data_what, line_skip));
      d.remove_prefix(nl + 1);
    }
  std::string unzipped;
  if (gz && !inflated) {
    unzipped = io::gunzip(d, data_what, {skip + need, io::kHeaderPromise});
    d = unzipped;
  }
  if (byte_skip == -1) {
    if (d.size() < need)
      throw FormatError(fmt::format("{}: header says {} bytes of data, the file holds {}", data_what, need, d.size()));
    d.remove_prefix(d.size() - need);
  } else {
    if (skip > d.size())
      throw FormatError(fmt::format("{}: 'byte skip: {}' is past the end of the data ({} bytes)", data_what, skip,
                                    d.size()));
    d.remove_prefix(skip);
  }
  Volume v = decode(d, dims, *type, endian == "big", spacing, data_what);
  v.origin = origin;
  v.source = what;
  check_volume_extent(v);
  return v;
}

Volume read_inr(const fs::path& path) {
  const std::string what = path.string();
  // The header from the first 64 KiB; the whole file only up to what the header promises.
  const bool gz = ends_with(path, ".gz");
  const std::string bytes = gz ? io::read_gzip(path, 1 << 16, true) : io::read_file_prefix(path, 1 << 16);
  if (bytes.rfind("#INRIMAGE-4#{", 0) != 0)
    throw FormatError(io::text_message(path, 1, 1, "not an INRIMAGE-4 file (no '#INRIMAGE-4#{' magic)"));
  const std::size_t end = bytes.find("##}");
  if (end == std::string::npos) throw FormatError(fmt::format("{}: header has no closing '##}}'", what));
  // The header is padded to a multiple of 256 bytes, ending with "##}\n".
  const std::size_t header = (end + 4 + 255) / 256 * 256;
  if (header > bytes.size())
    throw FormatError(fmt::format("{}: header of {} bytes is longer than the file ({} bytes)", what, header, bytes.size()));
  std::array<int, 3> dims{-1, -1, -1};
  int vdim = 1, pixsize = 0;
  std::string type_name, cpu = "decm";
  Vector3d spacing = Vector3d::Ones();
  io::TextReader in(std::string_view(bytes).substr(0, end), path, '#');
  while (in.next_line()) {
    const std::string_view line = in.rest_of_line();
    const auto eq = line.find('=');
    if (eq == std::string_view::npos) continue;
    const std::string key = trim(in.take(eq));
    in.take(1);
    const std::string value = trim(in.rest_of_line());
    if (key == "XDIM") dims[0] = header_number<int>(in, key);
    else if (key == "YDIM") dims[1] = header_number<int>(in, key);
    else if (key == "ZDIM") dims[2] = header_number<int>(in, key);
    else if (key == "VDIM") vdim = header_number<int>(in, key);
    else if (key == "TYPE") type_name = lower(value);
    else if (key == "PIXSIZE") pixsize = header_number<int>(in, key);
    else if (key == "CPU") cpu = lower(value);
    else if (key == "VX") spacing[0] = header_number<double>(in, key);
    else if (key == "VY") spacing[1] = header_number<double>(in, key);
    else if (key == "VZ") spacing[2] = header_number<double>(in, key);
  }
  for (int a = 0; a < 3; ++a)
    if (dims[a] < 0) throw FormatError(fmt::format("{}: missing {}DIM", what, "XYZ"[a]));
  if (vdim != 1) throw FormatError(fmt::format("{}: VDIM={} (only scalar volumes are supported)", what, vdim));
  VoxelType type;
  if (type_name == "float" && pixsize == 32) type = VoxelType::float32;
  else if (type_name == "float" && pixsize == 64) type = VoxelType::float64;
  else if (type_name == "unsigned fixed" && pixsize == 8) type = VoxelType::uint8;
  else if (type_name == "unsigned fixed" && pixsize == 16) type = VoxelType::uint16;
  else if (type_name == "unsigned fixed" && pixsize == 32) type = VoxelType::uint32;
  else if (type_name == "signed fixed" && pixsize == 8) type = VoxelType::int8;
  else if (type_name == "signed fixed" && pixsize == 16) type = VoxelType::int16;
  else if (type_name == "signed fixed" && pixsize == 32) type = VoxelType::int32;
  else
    throw FormatError(fmt::format("{}: unsupported TYPE='{}' with PIXSIZE={} bits", what, io::echo(type_name), pixsize));
  bool big = false;
  if (cpu == "sun" || cpu == "sgi") big = true;
  else if (cpu != "decm" && cpu != "alpha" && cpu != "pc")
    throw FormatError(fmt::format("{}: unknown CPU='{}' (decm, alpha, pc, sun, sgi)", what, io::echo(cpu)));
  const std::size_t bound = header + promised_bytes(dims, type, what);
  const std::string all =
      gz ? io::read_gzip(path, {bound, io::kHeaderPromise}) : io::read_file(path, {bound, io::kHeaderPromise});
  Volume v = decode(std::string_view(all).substr(header), dims, type, big, spacing, what);
  check_volume_extent(v);
  return v;
}

void write_nrrd(const Volume& volume, const fs::path& path) {
  fs::path raw = path;
  raw.replace_extension(".raw");
  write_file_atomically(raw, [&](std::ostream& out) {
    for (const float x : volume.values) {
      std::array<char, 4> b;
      std::memcpy(b.data(), &x, 4);
      if constexpr (std::endian::native == std::endian::big) std::reverse(b.begin(), b.end());
      out.write(b.data(), 4);
    }
  });
  write_file_atomically(path, [&](std::ostream& out) {
    const Vector3d& h = volume.spacing;
    const Vector3d& o = volume.origin;
    out << fmt::format("NRRD0004\n# {}\ntype: float\ndimension: 3\nspace dimension: 3\nsizes: {} {} {}\n"
                       "space directions: ({:.17g},0,0) (0,{:.17g},0) (0,0,{:.17g})\n"
                       "space origin: ({:.17g},{:.17g},{:.17g})\nendian: little\nencoding: raw\ndata file: {}\n",
                       volume.source, volume.dims[0], volume.dims[1], volume.dims[2], h.x(), h.y(), h.z(), o.x(),
                       o.y(), o.z(), raw.filename().string());
  });
}

Volume read_volume(const fs::path& path, const std::optional<RawVolumeLayout>& raw) {
  if (raw) return read_raw_volume(path, *raw);
  if (ends_with(path, ".nhdr") || ends_with(path, ".nrrd")) return read_nrrd(path);
  if (ends_with(path, ".inr") || ends_with(path, ".inr.gz")) return read_inr(path);
  throw InvalidInput(fmt::format("'{}': unknown volume format (.nhdr, .nrrd, .inr, .inr.gz; raw files need "
                                 "their dimensions and type)",
                                 path.string()));
}

// ---------------------------------------------------------------------------------------------
// Marschner–Lobb

namespace {
constexpr double kMlFm = 6.0, kMlAlpha = 0.25;
}

double marschner_lobb(const Vector3d& p) {
  using std::numbers::pi;
  const double r = std::hypot(p.x(), p.y());
  const double rho_r = std::cos(2 * pi * kMlFm * std::cos(pi * r / 2));
  return (1 - std::sin(pi * p.z() / 2) + kMlAlpha * (1 + rho_r)) / (2 * (1 + kMlAlpha));
}

Eigen::Vector3d marschner_lobb_gradient(const Vector3d& p) {
  using std::numbers::pi;
  const double r = std::hypot(p.x(), p.y());
  const double k = 1.0 / (2 * (1 + kMlAlpha));
  const double drho_r = pi * pi * kMlFm * std::sin(pi * r / 2) * std::sin(2 * pi * kMlFm * std::cos(pi * r / 2));
  Vector3d g(0, 0, -pi / 2 * std::cos(pi * p.z() / 2) * k);
  if (r > 0) {
    g.x() = k * kMlAlpha * drho_r * p.x() / r;
    g.y() = k * kMlAlpha * drho_r * p.y() / r;
  }
  return g;
}

Volume marschner_lobb_volume(int n) {
  if (n < 2 || n > 2048) throw InvalidInput(fmt::format("Marschner–Lobb grid size {} is outside [2, 2048]", n));
  Volume v;
  v.dims = {n, n, n};
  const double h = 2.0 / (n - 1);
  v.spacing = Vector3d::Constant(h);
  v.origin = Vector3d::Constant(-1.0);
  v.source = fmt::format("marschner-lobb {}^3", n);
  v.values.resize(static_cast<std::size_t>(n) * n * n);
  tbb::parallel_for(0, n, [&](int k) {
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) v.values[v.index(i, j, k)] = static_cast<float>(marschner_lobb(v.position(i, j, k)));
  });
  return v;
}

// ---------------------------------------------------------------------------------------------
// Conversion

namespace {

// Kuhn split of a cell: corner c sits at offset (c&1, c>>1&1, c>>2&1); the six monotone paths
// 0 → 7 (as core/synth.cpp split_cube), each ordered to positive orientation.
struct KuhnTets {
  std::array<std::array<int, 4>, 6> tets;
  KuhnTets() {
    static constexpr int paths[6][2] = {{1, 3}, {1, 5}, {2, 3}, {2, 6}, {4, 5}, {4, 6}};
    const auto off = [](int c) { return Vector3d(c & 1, (c >> 1) & 1, (c >> 2) & 1); };
    for (int t = 0; t < 6; ++t) {
      std::array<int, 4> v{0, paths[t][0], paths[t][1], 7};
      if ((off(v[1]) - off(v[0])).cross(off(v[2]) - off(v[0])).dot(off(v[3]) - off(v[0])) < 0) std::swap(v[1], v[2]);
      tets[t] = v;
    }
  }
};

// Per-axis weights of a 1-D reconstruction at index coordinate 2u/2 (u = twice the coordinate).
struct AxisWeights {
  int count = 0;
  std::array<int, 4> index{};
  std::array<double, 4> weight{};
};

AxisWeights axis_weights(int twice, int n, Reconstruction r) {
  AxisWeights w;
  if (twice % 2 == 0) {
    w.count = 1;
    w.index[0] = twice / 2;
    w.weight[0] = 1;
    return w;
  }
  const int i0 = (twice - 1) / 2;  // the sample below the midpoint
  if (r == Reconstruction::trilinear) {
    w.count = 2;
    w.index = {i0, i0 + 1, 0, 0};
    w.weight = {0.5, 0.5, 0, 0};
    return w;
  }
  // Catmull–Rom at t = ½: (−1, 9, 9, −1)/16, indices clamped to the grid (replicated border).
  w.count = 4;
  for (int a = 0; a < 4; ++a) w.index[a] = std::clamp(i0 - 1 + a, 0, n - 1);
  w.weight = {-1.0 / 16, 9.0 / 16, 9.0 / 16, -1.0 / 16};
  return w;
}

// The reconstruction at index point (twice[0], twice[1], twice[2]) / 2.
double reconstruct(const Volume& v, const std::array<int, 3>& twice, Reconstruction r) {
  const AxisWeights wx = axis_weights(twice[0], v.dims[0], r), wy = axis_weights(twice[1], v.dims[1], r),
                    wz = axis_weights(twice[2], v.dims[2], r);
  double s = 0;
  for (int c = 0; c < wz.count; ++c)
    for (int b = 0; b < wy.count; ++b) {
      double row = 0;
      for (int a = 0; a < wx.count; ++a) row += wx.weight[a] * v.at(wx.index[a], wy.index[b], wz.index[c]);
      s += wz.weight[c] * wy.weight[b] * row;
    }
  return s;
}

// Quadric V − f on the tetrahedron, relative to its centroid, from the symmetric 4×4 Bézier
// coefficient matrix B of f in barycentric coordinates (f = λᵀBλ, Σλ = 1).
Quadric patch_quadric(const std::array<Vector3d, 4>& corners, const Vector3d& centroid, Eigen::Matrix4d B,
                      double iso) {
  std::array<Vector3d, 4> q;
  for (int i = 0; i < 4; ++i) q[i] = corners[i] - centroid;
  Eigen::Matrix3d T;
  T << q[1] - q[0], q[2] - q[0], q[3] - q[0];
  const Eigen::Matrix3d Ti = T.inverse();
  // G̃: (y, 1) ↦ λ.
  Matrix4d G = Matrix4d::Zero();
  G.block<3, 3>(1, 0) = Ti;
  G.block<3, 1>(1, 3) = -Ti * q[0];
  G.block<1, 3>(0, 0) = -G.block<3, 3>(1, 0).colwise().sum();
  G(0, 3) = 1.0 - G.block<3, 1>(1, 3).sum();
  B = Matrix4d::Constant(iso) - B;  // V − f = λᵀ(V·11ᵀ − B)λ
  Matrix4d Q = G.transpose() * B * G;
  Q = 0.5 * (Q + Q.transpose());
  return Quadric::from_matrix(Q).normalized();
}

// Refinement depth of the quadratic patches' crossing test (core/bounds.h quadric_may_vanish).
constexpr int kRefineDepth = 6;

// Edge r–s of a tetrahedron (r < s) → its slot in the midpoint array: 01 02 03 12 13 23.
constexpr int kEdgeSlot[4][4] = {{-1, 0, 1, 2}, {0, -1, 3, 4}, {1, 3, -1, 5}, {2, 4, 5, -1}};

// The patch of one tetrahedron from its corner values f and edge-midpoint values mid (kEdgeSlot
// order; unused for linear patches), or none when its control net does not straddle V. Shared by
// the grid and the tet-mesh paths.
std::optional<TetPatch> iso_patch(const std::array<Vector3d, 4>& corners, const std::array<double, 4>& f,
                                  const std::array<double, 6>& mid, double V, const VolumeIsoOptions& options) {
  Eigen::Matrix4d B;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int r = 0; r < 4; ++r) {
    B(r, r) = f[r];
    lo = std::min(lo, B(r, r));
    hi = std::max(hi, B(r, r));
  }
  for (int r = 0; r < 4; ++r)
    for (int s = r + 1; s < 4; ++s) {
      // [linear] f = Σ fᵢλᵢ·Σλⱼ; [quadratic] Bernstein coefficient from the midpoint value.
      const double bij = options.linear ? 0.5 * (f[r] + f[s]) : 2.0 * mid[kEdgeSlot[r][s]] - 0.5 * (f[r] + f[s]);
      B(r, s) = B(s, r) = bij;
      lo = std::min(lo, bij);
      hi = std::max(hi, bij);
    }
  if (!(lo <= V && V <= hi) || lo == hi) return std::nullopt;
  TetPatch patch{corners, {}, options.colour};
  const Vector3d centroid = patch.centroid();
  if (options.linear) {
    // V − Σ fᵢλᵢ exactly linear: A = 0.
    Quadric lq = patch_quadric(corners, centroid, B, V);
    lq.A.setZero();
    patch.quadric = lq.normalized();
  } else {
    patch.quadric = patch_quadric(corners, centroid, B, V);
    // The net straddles V; refined nets (longest-edge splits) often do not: no surface inside.
    if (!quadric_may_vanish(corners, patch.quadric, centroid, kRefineDepth)) return std::nullopt;
  }
  return patch;
}

// V strictly inside the data range [vmin, vmax]. \throws InvalidInput.
void check_iso(double V, double vmin, double vmax, const std::string& what) {
  if (!std::isfinite(V) || !(V > vmin && V < vmax))
    throw InvalidInput(fmt::format("{}: iso-value {} is outside the data range ({}, {})", what, V, vmin, vmax));
}

}  // namespace

VolumeConversion convert_volume(const Volume& volume, const VolumeIsoOptions& options) {
  const auto& d = volume.dims;
  const std::string& what = volume.source;
  for (int a = 0; a < 3; ++a) {
    if (d[a] < 2)
      throw InvalidInput(fmt::format("{}: {} sample(s) along axis {}: an iso-surface needs at least 2", what, d[a], a));
    if (!(volume.spacing[a] > 0) || !std::isfinite(volume.spacing[a]))
      throw InvalidInput(fmt::format("{}: spacing {} along axis {} must be finite and > 0", what, volume.spacing[a], a));
  }
  check_volume_extent(volume);
  if (volume.values.size() != static_cast<std::size_t>(d[0]) * d[1] * d[2])
    throw InvalidInput(fmt::format("{}: {} values for a {}x{}x{} grid", what, volume.values.size(), d[0], d[1], d[2]));
  for (std::size_t i = 0; i < volume.values.size(); ++i)
    if (!std::isfinite(volume.values[i])) throw InvalidInput(fmt::format("{}: value {} is not finite", what, i));
  const auto [vmin, vmax] = volume.range();
  const double V = options.iso;
  check_iso(V, vmin, vmax, what);

  VolumeConversion out;
  out.value_min = vmin;
  out.value_max = vmax;
  out.cells = static_cast<std::size_t>(d[0] - 1) * (d[1] - 1) * (d[2] - 1);
  static const KuhnTets kuhn;
  const Reconstruction rec = options.reconstruction;
  // Control-net bound: a reconstructed value lies within [m − s·R, M + s·R] of its stencil's range
  // (s = half the sum of |negative weights|·2), a Bézier edge coefficient 2f_ij − (f_i+f_j)/2 within
  // another R; trilinear: R, Catmull–Rom (Σ|w| ≤ 1.25³): 2R.
  const int halo = (rec == Reconstruction::catmull_rom && !options.linear) ? 1 : 0;
  const double slack = options.linear ? 0.0 : (rec == Reconstruction::catmull_rom ? 2.0 : 1.0);

  struct Slab {
    std::vector<TetPatch> tets;
    std::size_t visited = 0, tested = 0;
  };
  std::vector<Slab> slabs(d[2] - 1);
  std::atomic<int> done{0};
  tbb::parallel_for(0, d[2] - 1, [&](int k) {
    Slab& slab = slabs[k];
    for (int j = 0; j < d[1] - 1; ++j)
      for (int i = 0; i < d[0] - 1; ++i) {
        double m = std::numeric_limits<double>::infinity(), M = -m;
        for (int c = k - halo; c <= k + 1 + halo; ++c)
          for (int b = j - halo; b <= j + 1 + halo; ++b)
            for (int a = i - halo; a <= i + 1 + halo; ++a) {
              const double x = volume.at(std::clamp(a, 0, d[0] - 1), std::clamp(b, 0, d[1] - 1), std::clamp(c, 0, d[2] - 1));
              m = std::min(m, x);
              M = std::max(M, x);
            }
        const double R = M - m;
        if (V < m - slack * R || V > M + slack * R || R == 0) continue;
        ++slab.visited;
        std::array<double, 8> f{};
        std::array<Vector3d, 8> p;
        for (int c = 0; c < 8; ++c) {
          const int a = i + (c & 1), b = j + ((c >> 1) & 1), e = k + ((c >> 2) & 1);
          f[c] = volume.at(a, b, e);
          p[c] = volume.position(a, b, e);
        }
        std::array<double, 64> mid{};  // mid[8a + b] for a < b, computed on first use
        std::array<bool, 64> has_mid{};
        const auto midpoint = [&](int a, int b) {
          if (a > b) std::swap(a, b);
          const int key = 8 * a + b;
          if (!has_mid[key]) {
            const std::array<int, 3> twice{2 * i + (a & 1) + (b & 1), 2 * j + ((a >> 1) & 1) + ((b >> 1) & 1),
                                           2 * k + ((a >> 2) & 1) + ((b >> 2) & 1)};
            mid[key] = reconstruct(volume, twice, rec);
            has_mid[key] = true;
          }
          return mid[key];
        };
        for (const auto& t : kuhn.tets) {
          ++slab.tested;
          const std::array<double, 4> ft{f[t[0]], f[t[1]], f[t[2]], f[t[3]]};
          std::array<double, 6> mt{};
          if (!options.linear)
            for (int r = 0; r < 4; ++r)
              for (int q = r + 1; q < 4; ++q) mt[kEdgeSlot[r][q]] = midpoint(t[r], t[q]);
          if (auto patch = iso_patch({p[t[0]], p[t[1]], p[t[2]], p[t[3]]}, ft, mt, V, options))
            slab.tets.push_back(std::move(*patch));
        }
      }
    const int n = ++done;
    if (options.progress) options.progress(static_cast<double>(n) / (d[2] - 1));
  });
  std::size_t total = 0;
  for (const auto& s : slabs) total += s.tets.size();
  out.model.tets.reserve(total);
  for (auto& s : slabs) {
    out.cells_visited += s.visited;
    out.tets_tested += s.tested;
    std::move(s.tets.begin(), s.tets.end(), std::back_inserter(out.model.tets));
  }
  log::debug("{}: iso {}: {} of {} cells visited, {} tetrahedra tested, {} kept", what, V, out.cells_visited,
             out.cells, out.tets_tested, out.model.tets.size());
  out.model.metadata["tetrahedra"] = "tessellation";  // the grid's Kuhn cells (core/model.h tetrahedra_tessellate)
  return out;
}

// ---------------------------------------------------------------------------------------------
// Tetrahedral meshes with per-vertex values

namespace {

// Vertex neighbours through the mesh edges, CSR: neighbours of v are adj[start[v] .. start[v+1]).
struct Adjacency {
  std::vector<std::size_t> start;
  std::vector<int> adj;
  std::span<const int> of(int v) const { return {adj.data() + start[v], adj.data() + start[v + 1]}; }
};

Adjacency vertex_adjacency(const TetMesh& mesh) {
  std::vector<std::pair<int, int>> e;
  e.reserve(mesh.tets.size() * 12);
  for (const auto& t : mesh.tets)
    for (int r = 0; r < 4; ++r)
      for (int q = 0; q < 4; ++q)
        if (r != q) e.emplace_back(t[r], t[q]);
  std::sort(e.begin(), e.end());
  e.erase(std::unique(e.begin(), e.end()), e.end());
  Adjacency a;
  a.start.assign(mesh.vertices.size() + 1, 0);
  for (const auto& [u, w] : e) ++a.start[u + 1];
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) a.start[v + 1] += a.start[v];
  a.adj.reserve(e.size());
  for (const auto& [u, w] : e) a.adj.push_back(w);
  return a;
}

constexpr std::size_t kMinFitNeighbours = 12;  // fewer 1-ring vertices: fit over the 2-ring
constexpr double kFitRankThreshold = 1e-7;     // relative pivot below which a column counts as dependent

}  // namespace

VertexGradients estimate_vertex_gradients(const TetMesh& mesh, std::span<const double> values) {
  if (values.size() != mesh.vertices.size())
    throw InvalidInput(fmt::format("{}: {} values for {} vertices", mesh.source, values.size(), mesh.vertices.size()));
  const Adjacency adj = vertex_adjacency(mesh);
  const int n = static_cast<int>(mesh.vertices.size());
  VertexGradients out;
  out.gradients.assign(mesh.vertices.size(), Vector3d::Zero());
  std::atomic<std::size_t> linear{0};
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 1024), [&](const tbb::blocked_range<int>& range) {
    std::vector<int> ring;
    Eigen::MatrixXd A;
    Eigen::VectorXd rhs;
    std::size_t local_linear = 0;
    for (int v = range.begin(); v < range.end(); ++v) {
      const auto one = adj.of(v);
      if (one.empty()) continue;  // not in any tetrahedron
      ring.assign(one.begin(), one.end());
      if (ring.size() < kMinFitNeighbours) {
        for (const int w : one)
          for (const int u : adj.of(w))
            if (u != v) ring.push_back(u);
        std::sort(ring.begin(), ring.end());
        ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
      }
      const Vector3d& x = mesh.vertices[v];
      double h2 = 0;
      for (const int w : ring) h2 += (mesh.vertices[w] - x).squaredNorm();
      const double h = std::sqrt(h2 / ring.size());  // unknowns scaled by h for conditioning
      const auto m = static_cast<Eigen::Index>(ring.size());
      A.resize(m, 9);
      rhs.resize(m);
      for (Eigen::Index r = 0; r < m; ++r) {
        const Vector3d d = (mesh.vertices[ring[r]] - x) / h;
        A.row(r) << d.x(), d.y(), d.z(), 0.5 * d.x() * d.x(), 0.5 * d.y() * d.y(), 0.5 * d.z() * d.z(), d.x() * d.y(),
            d.y() * d.z(), d.z() * d.x();
        rhs[r] = values[ring[r]] - values[v];
      }
      Vector3d g = Vector3d::Zero();
      bool done_fit = false;
      if (m >= 9) {
        Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
        qr.setThreshold(kFitRankThreshold);
        if (qr.rank() == 9) {
          g = qr.solve(rhs).head<3>() / h;
          done_fit = true;
        }
      }
      if (!done_fit) {
        // Linear fallback (any vertex of a non-degenerate tetrahedron has 3 independent edges).
        Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A.leftCols<3>());
        qr.setThreshold(kFitRankThreshold);
        if (qr.rank() == 3) g = qr.solve(rhs) / h;
        ++local_linear;
      }
      out.gradients[v] = g;
    }
    linear += local_linear;
  });
  out.linear_fits = linear;
  return out;
}

VolumeConversion convert_tet_mesh(const TetMesh& mesh, std::span<const double> values,
                                  const VolumeIsoOptions& options) {
  const std::string& what = mesh.source;
  validate_tet_mesh(mesh);
  if (values.size() != mesh.vertices.size())
    throw InvalidInput(fmt::format("{}: {} values for {} vertices", what, values.size(), mesh.vertices.size()));
  for (std::size_t i = 0; i < values.size(); ++i)
    if (!std::isfinite(values[i]))
      throw InvalidInput(fmt::format("{}: value {} (vertex {}) is not finite", what, values[i], i));
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  const double V = options.iso;
  check_iso(V, *lo, *hi, what);

  VolumeConversion out;
  out.value_min = *lo;
  out.value_max = *hi;
  out.cells = out.cells_visited = out.tets_tested = mesh.tets.size();
  VertexGradients grad;
  if (!options.linear) {
    grad = estimate_vertex_gradients(mesh, values);
    out.linear_gradients = grad.linear_fits;
  }
  if (options.progress) options.progress(0.1);

  const std::size_t block = 4096, blocks = (mesh.tets.size() + block - 1) / block;
  std::vector<std::vector<TetPatch>> kept(blocks);
  std::atomic<std::size_t> done{0};
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    const std::size_t end = std::min(mesh.tets.size(), (b + 1) * block);
    for (std::size_t i = b * block; i < end; ++i) {
      std::array<int, 4> t = mesh.tets[i];
      const auto X = [&](int k) -> const Vector3d& { return mesh.vertices[t[k]]; };
      if ((X(1) - X(0)).cross(X(2) - X(0)).dot(X(3) - X(0)) < 0) std::swap(t[1], t[2]);
      const std::array<double, 4> f{values[t[0]], values[t[1]], values[t[2]], values[t[3]]};
      std::array<double, 6> mid{};
      if (!options.linear)
        for (int r = 0; r < 4; ++r)
          for (int q = r + 1; q < 4; ++q) {
            // Cubic Hermite at the edge midpoint, in the order of the vertex ids so the value depends
            // on the edge only: (f_a + f_b)/2 + (∇f_a − ∇f_b)·(x_b − x_a)/8.
            const int a = std::min(t[r], t[q]), c = std::max(t[r], t[q]);
            mid[kEdgeSlot[r][q]] = 0.5 * (values[a] + values[c]) +
                                   (grad.gradients[a] - grad.gradients[c]).dot(mesh.vertices[c] - mesh.vertices[a]) / 8;
          }
      if (auto patch = iso_patch({X(0), X(1), X(2), X(3)}, f, mid, V, options)) kept[b].push_back(std::move(*patch));
    }
    const std::size_t d = ++done;
    if (options.progress) options.progress(0.1 + 0.9 * static_cast<double>(d) / blocks);
  });
  std::size_t total = 0;
  for (const auto& k : kept) total += k.size();
  out.model.tets.reserve(total);
  for (auto& k : kept) std::move(k.begin(), k.end(), std::back_inserter(out.model.tets));
  log::debug("{}: iso {}: {} tetrahedra, {} kept; {} of {} vertex gradients from the linear fallback", what, V,
             mesh.tets.size(), out.model.tets.size(), out.linear_gradients, mesh.vertices.size());
  out.model.metadata["tetrahedra"] = "tessellation";  // the mesh's cells
  return out;
}

}  // namespace quadrix
