#pragma once
/// Test helpers for the .qxm reader (header-only, self-contained):
/// - a tiny, independent PLY writer for the .qxm profile in every encoding (ASCII, binary
///   little- and big-endian; double or float columns), so tests do not rely on write_model alone;
/// - a deterministic sample Model holding all three primitive kinds;
/// - make_malformed_corpus(dir): ≥ 24 malformed .qxm files, each paired with a substring its
///   FormatError message must contain (besides the file name). Every case must make read_model
///   throw FormatError (and `quadrix info` exit with code 3).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/model.h"
#include "core/model_io.h"

namespace quadrix::test {

struct MalformedCase {
  std::filesystem::path path;
  std::string expected;  ///< substring of the FormatError message (the file name is checked separately)
};

/// A per-test temporary folder, removed (with its content) on destruction.
class ScratchDir {
public:
  explicit ScratchDir(const std::string& tag) {
    std::random_device rd;
    path_ = std::filesystem::temp_directory_path() /
            ("quadrix-" + tag + "-" + std::to_string(rd()) + "-" + std::to_string(rd()));
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

private:
  std::filesystem::path path_;
};

// ------------------------------------------------------------------ a tiny PLY writer

struct PlyProp {
  std::string type;  ///< char uchar short ushort int uint float double (or anything, verbatim)
  std::string name;
  std::string list_count;  ///< non-empty: a list property with this count type; the row holds count, entries
};

struct PlyElem {
  std::string name;
  std::vector<PlyProp> props;
  std::vector<std::vector<double>> rows;
  std::string count_override;  ///< written instead of rows.size() when non-empty
};

struct PlyDoc {
  std::string magic = "ply";
  std::string format_override;  ///< the whole format line, when non-empty
  std::vector<std::string> comments;
  std::vector<PlyElem> elements;
  bool end_header = true;
  PlyElem& element(const std::string& name) {
    for (auto& e : elements)
      if (e.name == name) return e;
    throw std::runtime_error("no element " + name);
  }
  /// Column of a scalar property (valid while no list precedes it).
  static std::size_t column(const PlyElem& e, const std::string& prop) {
    for (std::size_t i = 0; i < e.props.size(); ++i)
      if (e.props[i].name == prop) return i;
    throw std::runtime_error("no property " + prop);
  }
  void set(const std::string& elem, std::size_t row, const std::string& prop, double v) {
    PlyElem& e = element(elem);
    e.rows.at(row).at(column(e, prop)) = v;
  }
  void remove_property(const std::string& elem, const std::string& prop) {
    PlyElem& e = element(elem);
    const std::size_t c = column(e, prop);
    e.props.erase(e.props.begin() + static_cast<std::ptrdiff_t>(c));
    for (auto& r : e.rows) r.erase(r.begin() + static_cast<std::ptrdiff_t>(c));
  }
};

inline std::size_t ply_type_size(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "double" || t == "float64") return 8;
  return 4;
}

inline void append_binary(std::string& out, const std::string& t, double v, bool big_endian) {
  unsigned char b[8];
  std::size_t n = ply_type_size(t);
  auto put = [&](auto x) { std::memcpy(b, &x, sizeof(x)); };
  if (t == "char" || t == "int8")
    put(static_cast<std::int8_t>(std::llround(v)));
  else if (t == "uchar" || t == "uint8")
    put(static_cast<std::uint8_t>(std::llround(v)));
  else if (t == "short" || t == "int16")
    put(static_cast<std::int16_t>(std::llround(v)));
  else if (t == "ushort" || t == "uint16")
    put(static_cast<std::uint16_t>(std::llround(v)));
  else if (t == "int" || t == "int32")
    put(static_cast<std::int32_t>(std::llround(v)));
  else if (t == "uint" || t == "uint32")
    put(static_cast<std::uint32_t>(std::llround(v)));
  else if (t == "double" || t == "float64")
    put(v);
  else
    put(static_cast<float>(v));
  if (big_endian)
    for (std::size_t i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
  out.append(reinterpret_cast<const char*>(b), n);
}

inline std::string ascii_value(const std::string& t, double v) {
  char buf[64];
  if (t == "float" || t == "float32" || t == "double" || t == "float64" || !std::isfinite(v))
    std::snprintf(buf, sizeof buf, "%.17g", v);
  else
    std::snprintf(buf, sizeof buf, "%lld", std::llround(v));
  return buf;
}

/// Encodes doc; encoding is "ascii", "binary_little_endian" or "binary_big_endian".
inline std::string encode_ply(const PlyDoc& doc, const std::string& encoding) {
  std::string out = doc.magic + "\n";
  out += doc.format_override.empty() ? "format " + encoding + " 1.0\n" : doc.format_override + "\n";
  for (const auto& c : doc.comments) out += "comment " + c + "\n";
  for (const auto& e : doc.elements) {
    out += "element " + e.name + " " + (e.count_override.empty() ? std::to_string(e.rows.size()) : e.count_override) +
           "\n";
    for (const auto& p : e.props)
      out += p.list_count.empty() ? "property " + p.type + " " + p.name + "\n"
                                  : "property list " + p.list_count + " " + p.type + " " + p.name + "\n";
  }
  if (doc.end_header) out += "end_header\n";
  const bool ascii = encoding == "ascii";
  const bool be = encoding == "binary_big_endian";
  for (const auto& e : doc.elements) {
    for (const auto& row : e.rows) {
      std::size_t k = 0;
      std::string line;
      auto put = [&](const std::string& t) {
        const double v = row.at(k++);
        if (ascii) {
          if (!line.empty()) line += ' ';
          line += ascii_value(t, v);
        } else
          append_binary(out, t, v, be);
        return v;
      };
      for (const auto& p : e.props) {
        if (k >= row.size()) break;  // a deliberately short row
        if (p.list_count.empty()) {
          put(p.type);
          continue;
        }
        const double n = put(p.list_count);
        for (long long i = 0; i < static_cast<long long>(n) && k < row.size(); ++i) put(p.type);
      }
      if (ascii) out += line + "\n";
    }
  }
  return out;
}

inline void write_bytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

inline std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// The .qxm profile of m as a PlyDoc (optional columns present when any primitive has them);
/// real_type is the type of the non-integer columns ("double" or "float").
inline PlyDoc qxm_doc(const Model& m, const std::string& real_type = "double") {
  PlyDoc d;
  d.comments.push_back("quadrix-format 1");
  for (const auto& [k, v] : m.metadata) d.comments.push_back(k + " " + v);
  const std::vector<std::string> k = {"k_xx", "k_yy", "k_zz", "k_xy", "k_yz", "k_zx", "k_x", "k_y", "k_z", "k_1"};
  auto reals = [&](PlyElem& e, std::initializer_list<std::string> names) {
    for (const auto& n : names) e.props.push_back({real_type, n, ""});
  };
  auto coeffs = [&](PlyElem& e) {
    for (const auto& n : k) e.props.push_back({real_type, n, ""});
  };
  auto colour = [&](PlyElem& e) {
    for (const char* n : {"red", "green", "blue"}) e.props.push_back({"uchar", n, ""});
  };
  auto push_colour = [](std::vector<double>& r, const std::optional<Rgb>& c) {
    const Rgb v = c.value_or(Rgb{0, 0, 0});
    r.insert(r.end(), {double(v[0]), double(v[1]), double(v[2])});
  };
  int clip = 0;  // clip plane groups: as many as the patch with the most has
  bool sc = false, tc = false, gc = false;
  for (const auto& s : m.slims) clip = std::max(clip, s.clips.size()), sc |= s.colour.has_value();
  for (const auto& t : m.tets) tc |= t.colour.has_value();
  for (const auto& g : m.glyphs) gc |= g.colour.has_value();
  if (!m.slims.empty()) {
    PlyElem e{"slim", {}, {}, {}};
    reals(e, {"x", "y", "z", "radius"});
    coeffs(e);
    for (int k = 0; k < clip; ++k) {
      const std::string p = k == 0 ? "clip_" : "clip" + std::to_string(k + 1) + "_";
      reals(e, {p + "nx", p + "ny", p + "nz", p + "d"});
    }
    if (sc) colour(e);
    for (const auto& s : m.slims) {
      std::vector<double> r = {s.centre.x(), s.centre.y(), s.centre.z(), s.radius};
      for (double v : s.local.coefficients()) r.push_back(v);
      for (int k = 0; k < clip; ++k) {
        const ClipPlane p = k < s.clips.size() ? s.clips[k] : ClipPlane{};
        r.insert(r.end(), {p.n.x(), p.n.y(), p.n.z(), p.d});
      }
      if (sc) push_colour(r, s.colour);
      e.rows.push_back(r);
    }
    d.elements.push_back(e);
  }
  if (!m.tets.empty()) {
    PlyElem e{"tet", {}, {}, {}};
    for (int i = 0; i < 4; ++i) {
      const std::string s = std::to_string(i);
      reals(e, {"x" + s, "y" + s, "z" + s});
    }
    coeffs(e);
    if (tc) colour(e);
    for (const auto& t : m.tets) {
      std::vector<double> r;
      for (const auto& p : t.corners) r.insert(r.end(), {p.x(), p.y(), p.z()});
      for (double v : t.quadric.coefficients()) r.push_back(v);
      if (tc) push_colour(r, t.colour);
      e.rows.push_back(r);
    }
    d.elements.push_back(e);
  }
  if (!m.glyphs.empty()) {
    PlyElem e{"glyph", {{"uchar", "kind", ""}}, {}, {}};
    reals(e, {"x", "y", "z", "radius", "a0x", "a0y", "a0z", "a1x", "a1y", "a1z", "a2x", "a2y", "a2z"});
    if (gc) colour(e);
    for (const auto& g : m.glyphs) {
      std::vector<double> r = {double(static_cast<int>(g.kind)), g.centre.x(), g.centre.y(), g.centre.z(), g.radius};
      for (int c = 0; c < 3; ++c) r.insert(r.end(), {g.axes(0, c), g.axes(1, c), g.axes(2, c)});
      if (gc) push_colour(r, g.colour);
      e.rows.push_back(r);
    }
    d.elements.push_back(e);
  }
  return d;
}

/// Deterministic model with 3 slims, 3 tets and 3 glyphs (one per kind); full-mantissa doubles.
/// with_optional: clip planes on some slims (not all), colours on every primitive.
inline Model make_sample_model(bool with_optional) {
  std::mt19937_64 rng(20240611);
  auto u = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };  // [0, 1), portable
  auto vec = [&](double s) { return Eigen::Vector3d(s * (2 * u() - 1), s * (2 * u() - 1), s * (2 * u() - 1)); };
  auto coeffs = [&] {
    QuadricCoefficients k;
    for (double& v : k) v = 2 * u() - 1;
    return k;
  };
  auto rgb = [&] { return Rgb{std::uint8_t(rng() & 255), std::uint8_t(rng() & 255), std::uint8_t(rng() & 255)}; };
  Model m;
  m.metadata["producer"] = "quadrix test";
  m.metadata["units"] = "mm";
  for (int i = 0; i < 3; ++i) {
    SlimPatch s;
    s.centre = vec(10);
    s.radius = 0.25 + u();
    s.local = Quadric::from_coefficients(coeffs());
    // None on the second patch, three on the third (revision 4's clip2_* and clip3_*).
    if (with_optional && i != 1)
      for (int k = 0; k < (i == 2 ? 3 : 1); ++k) s.clips.add(ClipPlane{vec(1) + Eigen::Vector3d(0.1, 0, 0), 2 * u() - 1});
    if (with_optional) s.colour = rgb();
    m.slims.push_back(s);
  }
  for (int i = 0; i < 3; ++i) {
    TetPatch t;
    const Eigen::Vector3d o = vec(10);
    t.corners = {o, o + Eigen::Vector3d(1 + u(), u() * 0.1, 0), o + Eigen::Vector3d(0, 1 + u(), u() * 0.1),
                 o + Eigen::Vector3d(u() * 0.1, 0, 1 + u())};
    t.quadric = Quadric::from_coefficients(coeffs());
    if (with_optional) t.colour = rgb();
    m.tets.push_back(t);
  }
  for (int i = 0; i < 3; ++i) {
    Glyph g;
    g.kind = static_cast<GlyphKind>(i);
    g.centre = vec(10);
    g.radius = 0.1 + u();
    g.axes = Eigen::Matrix3d::Identity() * (0.5 + u());
    g.axes.col(0) += vec(0.2);
    g.axes.col(1) += vec(0.2);
    if (with_optional) g.colour = rgb();
    m.glyphs.push_back(g);
  }
  return m;
}

/// Writes the malformed corpus into dir and returns the cases.
inline std::vector<MalformedCase> make_malformed_corpus(const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  std::vector<MalformedCase> cases;
  const Model model = make_sample_model(true);
  const std::string le = "binary_little_endian", be = "binary_big_endian", ascii = "ascii";
  auto add = [&](const std::string& name, const std::string& bytes, const std::string& expected) {
    write_bytes(dir / name, bytes);
    cases.push_back({dir / name, expected});
  };
  auto add_doc = [&](const std::string& name, const PlyDoc& d, const std::string& enc, const std::string& expected) {
    add(name, encode_ply(d, enc), expected);
  };

  // The valid file as write_model writes it, and its layout.
  const std::filesystem::path valid = dir / "valid_reference.qxm.tmp";
  write_model(model, valid, {.encoding = ModelEncoding::full});
  const std::string base = read_bytes(valid);
  std::filesystem::remove(valid);
  const std::size_t body = base.find("end_header\n") + 11;
  const PlyDoc doc = qxm_doc(model);
  auto row_size = [&](const std::string& e) {
    std::size_t n = 0;
    for (const auto& p : const_cast<PlyDoc&>(doc).element(e).props) n += ply_type_size(p.type);
    return n;
  };
  const std::size_t slim_row = row_size("slim"), tet_row = row_size("tet"), glyph_row = row_size("glyph");
  const std::size_t tet_start = body + 3 * slim_row, glyph_start = tet_start + 3 * tet_row;
  if (glyph_start + 3 * glyph_row != base.size()) throw std::runtime_error("malformed corpus: unexpected layout");

  // Empty, magic, format and header-level faults.
  add("empty.qxm", "", "empty file");
  add("bad_magic.qxm", "plx" + base.substr(3), "magic");
  {
    PlyDoc d = doc;
    d.format_override = "format binary_middle_endian 1.0";
    add_doc("bad_format.qxm", d, le, "binary_middle_endian");
    d.format_override = "format binary_little_endian 2.0";
    add_doc("bad_ply_version.qxm", d, le, "version");
  }
  {
    PlyDoc d = doc;
    d.comments[0] = "quadrix-format " + std::to_string(kQxmFormatVersion + 1);
    add_doc("future_version.qxm", d, le, "unsupported quadrix-format");
    d.comments.erase(d.comments.begin());
    add_doc("plain_ply.qxm", d, le, "not a .qxm file");
  }
  {
    PlyDoc d = doc;
    d.end_header = false;
    for (auto& e : d.elements) e.rows.clear(), e.count_override = "3";
    add_doc("no_end_header.qxm", d, le, "end_header");
  }
  add("truncated_header.qxm", base.substr(0, body / 2), "end_header");
  {
    PlyDoc d = doc;
    d.element("slim").props[0].type = "float128";
    add_doc("unknown_type.qxm", d, le, "float128");
  }
  {
    PlyDoc d = doc;
    d.remove_property("slim", "radius");
    add_doc("missing_radius.qxm", d, le, "property 'radius'");
    PlyDoc t = doc;
    t.remove_property("tet", "k_1");
    add_doc("missing_tet_k1.qxm", t, le, "property 'k_1'");
  }

  // Truncation in every section.
  add("truncated_slim.qxm", base.substr(0, body + slim_row + slim_row / 2), "element 'slim' row 1");
  add("truncated_tet.qxm", base.substr(0, tet_start + 2 * tet_row + 5), "element 'tet' row 2");
  add("truncated_glyph.qxm", base.substr(0, glyph_start + glyph_row / 2), "element 'glyph' row 0");
  add("one_byte_short.qxm", base.substr(0, base.size() - 1), "element 'glyph' row 2");

  // Counts.
  {
    PlyDoc d = doc;
    d.element("slim").count_override = "1000000000000000";
    add_doc("absurd_count.qxm", d, le, "element 'slim'");
    d.element("slim").count_override = "99999999999999999999999999";
    add_doc("overflowing_count.qxm", d, le, "element 'slim'");
    PlyDoc t = doc;
    t.element("tet").count_override = "-5";
    add_doc("negative_count.qxm", t, le, "negative");
  }
  {  // A list property in slim (to be skipped) with bad counts.
    PlyDoc d = doc;
    PlyElem& s = d.element("slim");
    s.props.push_back({"int", "extra", "int"});
    for (auto& r : s.rows) r.insert(r.end(), {2, 7, 8});
    PlyDoc neg = d;
    auto& n = neg.element("slim").rows[1];
    n.resize(n.size() - 3);
    n.push_back(-1);  // list count −1, no entries
    add_doc("negative_list_count.qxm", neg, le, "list count -1 is negative");
    PlyDoc big = d;
    auto& r = big.element("slim").rows[2];
    r[r.size() - 3] = 2000000000;
    r.resize(r.size() - 2);
    add_doc("absurd_list_count.qxm", big, le, "element 'slim' row 2 property 'extra'");
  }

  // Non-finite values and invalid primitives.
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  auto with = [&](const std::string& e, std::size_t row, const std::string& p, double v) {
    PlyDoc d = doc;
    d.set(e, row, p, v);
    return d;
  };
  add_doc("nan_slim.qxm", with("slim", 1, "y", nan), le, "element 'slim' row 1 property 'y'");
  add_doc("inf_slim_radius.qxm", with("slim", 0, "radius", -inf), le, "element 'slim' row 0 property 'radius'");
  add_doc("inf_tet.qxm", with("tet", 1, "k_x", inf), le, "element 'tet' row 1 property 'k_x'");
  add_doc("nan_glyph.qxm", with("glyph", 2, "a1y", nan), le, "element 'glyph' row 2 property 'a1y'");
  add_doc("be_inf_clip.qxm", with("slim", 2, "clip_d", inf), be, "element 'slim' row 2 property 'clip_d'");
  add_doc("ascii_nan_glyph.qxm", with("glyph", 0, "x", nan), ascii, "element 'glyph' row 0 property 'x'");
  add_doc("negative_radius.qxm", with("slim", 2, "radius", -0.5), le, "element 'slim' row 2 property 'radius'");
  add_doc("zero_sphere_radius.qxm", with("glyph", 0, "radius", 0.0), le, "element 'glyph' row 0 property 'radius'");
  add_doc("bad_glyph_kind.qxm", with("glyph", 1, "kind", 7), le, "element 'glyph' row 1 property 'kind'");
  add_doc("bad_colour.qxm", with("tet", 0, "green", 300), ascii, "element 'tet' row 0 property 'green'");
  {
    PlyDoc d = doc;
    for (const char* axis : {"x", "y", "z"}) {  // corner 3 := corner 0
      const double v = d.element("tet").rows[1][PlyDoc::column(d.element("tet"), std::string(axis) + "0")];
      d.set("tet", 1, std::string(axis) + "3", v);
    }
    add_doc("degenerate_tet.qxm", d, le, "element 'tet' row 1");
  }
  {
    PlyDoc d = doc;
    for (const char* p : {"a2x", "a2y", "a2z"}) d.set("glyph", 1, p, 0.0);
    add_doc("flat_ellipsoid.qxm", d, le, "element 'glyph' row 1");
    PlyDoc c = doc;
    for (const char* p : {"a0x", "a0y", "a0z"}) c.set("glyph", 2, p, 0.0);
    add_doc("zero_cylinder_axis.qxm", c, le, "element 'glyph' row 2");
  }

  // Encoding faults.
  {
    std::string swapped = base;
    swapped.replace(swapped.find("binary_little_endian"), 20, "binary_big_endian");
    add("wrong_endianness.qxm", swapped, "");  // must fail somewhere; the place is not asserted
  }
  {
    std::string text = encode_ply(doc, ascii);
    const std::size_t at = text.find('\n', text.find("end_header\n") + 11) + 1;  // slim row 1
    text.replace(at, text.find(' ', at) - at, "abc");
    add("ascii_token.qxm", text, "'abc' is not a number");
    PlyDoc d = doc;
    d.element("tet").rows[0].pop_back();
    add_doc("ascii_too_few.qxm", d, ascii, "element 'tet' row 0");
  }
  return cases;
}

/// A malformed input for one of the kit's readers: which reader, the file, a message fragment.
struct IoCase {
  std::string reader;  ///< "model", "mesh" or "points"
  std::filesystem::path path;
  std::string expected;
};

/// The I/O kit's hardening cases (counts against the bytes, trailing data, extreme indices,
/// long and control-byte tokens), for read_model, read_mesh and read_points.
inline std::vector<IoCase> make_io_corpus(const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  std::vector<IoCase> cases;
  auto add = [&](const std::string& reader, const std::string& name, const std::string& bytes, const std::string& expected) {
    write_bytes(dir / name, bytes);
    cases.push_back({reader, dir / name, expected});
  };
  const Model model = make_sample_model(false);
  const PlyDoc doc = qxm_doc(model);
  {  // .qxm counts one too small / too large / zero, and a binary header over an ASCII body
    PlyDoc d = doc;
    d.element("slim").count_override = "2";
    add("model", "count_small.qxm", encode_ply(d, "binary_little_endian"), "trailing data");
    d.element("slim").count_override = "4";
    add("model", "count_large.qxm", encode_ply(d, "binary_little_endian"), "element 'glyph'");
    PlyDoc z = doc;
    z.element("slim").count_override = "0";
    add("model", "count_zero.qxm", encode_ply(z, "binary_little_endian"), "trailing data");
    std::string mixed = encode_ply(doc, "ascii");
    mixed.replace(mixed.find("format ascii"), 12, "format binary_little_endian");
    add("model", "binary_header_ascii_body.qxm", mixed, "");
    std::string ascii_tail = encode_ply(doc, "ascii") + "1 2 3\n";
    add("model", "ascii_trailing.qxm", ascii_tail, "trailing data");
  }
  // OFF: 2^30 vertices declared in a tiny file; trailing data after the faces.
  add("mesh", "huge_count.off", "OFF\n1073741824 1 0\n0 0 0\n", "1073741824 vertices");
  add("points", "huge_count_points.off", "OFF\n1073741824 0 0\n0 0 0\n", "1073741824 vertices");
  add("mesh", "trailing.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n0 0 1\n", "trailing data");
  add("mesh", "face_count_bomb.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2000000000 0 1 2\n", "2000000000 vertices");
  // OBJ: the most negative 64-bit index, and one past it.
  add("mesh", "int64_min.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -9223372036854775808\n", "reaches before the first vertex");
  add("mesh", "int64_overflow.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -9223372036854775809\n", "not a vertex reference");
  // Echoed tokens: a 300,000-digit number and control bytes are cut and escaped.
  add("points", "long_token.xyz", "1 2 3\n1 " + std::string(300000, '7') + "x 3\n", "bytes)");
  add("points", "control.xyz", "1 2 \x1b[31m\n", "\\x1b");
  // Found by fuzzing (UBSan: a count past long long): refused against the file's size.
  add("points", "count_huge.pts", "\n44444444444444444444\n\r\n3\n3", "count_huge.pts:2:");
  add("points", "count_big.pts", "1000\n0 0 0\n", "declares 1000 points, more than the file's 11 bytes can hold");
  // PLY points with bytes after the declared vertices; a mesh PLY with a list beyond the file.
  {
    PlyDoc d;
    PlyElem v{"vertex", {{"float", "x", ""}, {"float", "y", ""}, {"float", "z", ""}}, {{0, 0, 0}, {1, 0, 0}}, {}};
    d.elements.push_back(v);
    add("points", "trailing_points.ply", encode_ply(d, "binary_little_endian") + "junk", "trailing data");
    add("points", "trailing_points_ascii.ply", encode_ply(d, "ascii") + "4 5 6\n", "trailing data");
    PlyElem f{"face", {{"int", "vertex_indices", "uchar"}}, {{3, 0, 1, 7}}, {}};
    d.elements.push_back(f);
    add("mesh", "bad_index.ply", encode_ply(d, "binary_big_endian"), "vertex index 7 out of range");
  }
  // STL: a binary count that disagrees with the size; ASCII with garbage after endsolid.
  {
    std::string b(84, '\0');
    b[80] = 5;
    add("mesh", "short.stl", b + std::string(50, '\0'), "5 triangles");
    add("mesh", "trailing.stl",
        "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
        "endsolid t\nmore\n",
        "trailing data");
  }
  return cases;
}

}  // namespace quadrix::test
