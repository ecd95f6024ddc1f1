#include "core/io/ply.h"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>

#include <fmt/format.h>

#include "core/error.h"
#include "core/io/file.h"

namespace quadrix::ply {
namespace {

static_assert(std::endian::native == std::endian::little, "binary PLY I/O assumes a little-endian host");

struct TypeName {
  std::string_view name;
  Type type;
};
constexpr TypeName kTypeNames[] = {
    {"char", Type::int8},     {"int8", Type::int8},       {"uchar", Type::uint8},    {"uint8", Type::uint8},
    {"short", Type::int16},   {"int16", Type::int16},     {"ushort", Type::uint16},  {"uint16", Type::uint16},
    {"int", Type::int32},     {"int32", Type::int32},     {"uint", Type::uint32},    {"uint32", Type::uint32},
    {"float", Type::float32}, {"float32", Type::float32}, {"double", Type::float64}, {"float64", Type::float64},
};

bool parse_type(std::string_view s, Type& t) {
  for (const auto& tn : kTypeNames)
    if (tn.name == s) {
      t = tn.type;
      return true;
    }
  return false;
}

bool is_integer_type(Type t) { return t != Type::float32 && t != Type::float64; }

double type_min(Type t) {
  switch (t) {
    case Type::int8:
      return -128.0;
    case Type::uint8:
      return 0.0;
    case Type::int16:
      return -32768.0;
    case Type::uint16:
      return 0.0;
    case Type::int32:
      return -2147483648.0;
    case Type::uint32:
      return 0.0;
    default:
      return -std::numeric_limits<double>::infinity();
  }
}
double type_max(Type t) {
  switch (t) {
    case Type::int8:
      return 127.0;
    case Type::uint8:
      return 255.0;
    case Type::int16:
      return 32767.0;
    case Type::uint16:
      return 65535.0;
    case Type::int32:
      return 2147483647.0;
    case Type::uint32:
      return 4294967295.0;
    default:
      return std::numeric_limits<double>::infinity();
  }
}

std::vector<std::string_view> split_words(std::string_view line) {
  std::vector<std::string_view> words;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    std::size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t') ++j;
    if (j > i) words.push_back(line.substr(i, j - i));
    i = j;
  }
  return words;
}

/// Text after the first word of line (the keyword) and its following blanks.
std::string rest_after_keyword(std::string_view line) {
  std::size_t i = 0;
  while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
  while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
  while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
  std::string_view rest = line.substr(i);
  while (!rest.empty() && (rest.back() == ' ' || rest.back() == '\t')) rest.remove_suffix(1);
  return std::string(rest);
}

template <class T>
T load(const char* p, bool swap) {
  using U = std::conditional_t<sizeof(T) == 1, std::uint8_t,
                               std::conditional_t<sizeof(T) == 2, std::uint16_t,
                                                  std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>>;
  U u;
  std::memcpy(&u, p, sizeof(U));
  if (swap) {
    if constexpr (sizeof(U) == 2) u = static_cast<U>(__builtin_bswap16(u));
    if constexpr (sizeof(U) == 4) u = __builtin_bswap32(u);
    if constexpr (sizeof(U) == 8) u = __builtin_bswap64(u);
  }
  return std::bit_cast<T>(u);
}

double load_value(const char* p, Type t, bool swap) {
  switch (t) {
    case Type::int8:
      return load<std::int8_t>(p, swap);
    case Type::uint8:
      return load<std::uint8_t>(p, swap);
    case Type::int16:
      return load<std::int16_t>(p, swap);
    case Type::uint16:
      return load<std::uint16_t>(p, swap);
    case Type::int32:
      return load<std::int32_t>(p, swap);
    case Type::uint32:
      return load<std::uint32_t>(p, swap);
    case Type::float32:
      return load<float>(p, swap);
    case Type::float64:
      return load<double>(p, swap);
  }
  return 0.0;
}

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

}  // namespace

std::size_t type_size(Type t) {
  switch (t) {
    case Type::int8:
    case Type::uint8:
      return 1;
    case Type::int16:
    case Type::uint16:
      return 2;
    case Type::int32:
    case Type::uint32:
    case Type::float32:
      return 4;
    case Type::float64:
      return 8;
  }
  return 0;
}

std::string_view type_name(Type t) {
  switch (t) {
    case Type::int8:
      return "char";
    case Type::uint8:
      return "uchar";
    case Type::int16:
      return "short";
    case Type::uint16:
      return "ushort";
    case Type::int32:
      return "int";
    case Type::uint32:
      return "uint";
    case Type::float32:
      return "float";
    case Type::float64:
      return "double";
  }
  return "?";
}

int Element::find(std::string_view n) const {
  for (std::size_t i = 0; i < properties.size(); ++i)
    if (properties[i].name == n) return static_cast<int>(i);
  return -1;
}

const Element* Header::find(std::string_view n) const {
  for (const auto& e : elements)
    if (e.name == n) return &e;
  return nullptr;
}

std::uint64_t Table::byte_offset(std::size_t row, std::size_t col) const {
  const std::int64_t c = col < column_offsets.size() ? column_offsets[col] : -1;
  return row_offsets[row] + static_cast<std::uint64_t>(std::max<std::int64_t>(c, 0));
}

std::string File::message(std::string_view element, std::int64_t row, std::string_view property, std::uint64_t byte,
                          std::string_view what) const {
  std::string where;
  auto add = [&](const std::string& part) { where += (where.empty() ? "" : " ") + part; };
  if (!element.empty()) add(fmt::format("element '{}'", io::echo(element)));
  if (row >= 0) add(fmt::format("row {}", row));
  if (!property.empty()) add(fmt::format("property '{}'", io::echo(property)));
  // Element-level faults keep `… at byte B: what` after the place; the rest read `FILE: byte B: what`.
  if (where.empty()) return byte == kNoByte ? fmt::format("{}: {}", path_.string(), what) : io::byte_message(path_, byte, what);
  if (byte != kNoByte) add(fmt::format("at byte {}", byte));
  return fmt::format("{}: {}: {}", path_.string(), where, what);
}

File File::open(const std::filesystem::path& path) { return from_bytes(io::read_file(path), path); }

File File::from_bytes(std::string bytes, const std::filesystem::path& path) {
  File f;
  f.path_ = path;
  f.bytes_ = std::move(bytes);
  const std::string_view s = f.bytes_;
  auto fail = [&](std::size_t byte, std::string_view what) { throw FormatError(f.message({}, -1, {}, byte, what)); };
  if (s.empty()) fail(0, "empty file (expected the PLY magic 'ply')");
  if (!(s.starts_with("ply\n") || s.starts_with("ply\r\n")))
    fail(0, "bad magic: not a PLY file (expected a first line 'ply')");

  Header& h = f.header_;
  bool has_format = false;
  std::size_t pos = s.find('\n') + 1;
  int line_no = 1;
  while (true) {
    ++line_no;
    const std::size_t eol = s.find('\n', pos);
    if (eol == std::string_view::npos) fail(pos, "missing 'end_header' (header runs to the end of the file)");
    std::string_view line = s.substr(pos, eol - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    const std::size_t line_start = pos;
    pos = eol + 1;
    const auto words = split_words(line);
    auto bad = [&](std::string_view what) { fail(line_start, fmt::format("header line {}: {}", line_no, what)); };
    if (words.empty()) continue;
    const std::string_view kw = words[0];
    if (kw == "end_header") {
      break;
    } else if (kw == "comment") {
      h.comments.push_back(rest_after_keyword(line));
    } else if (kw == "obj_info") {
      h.obj_info.push_back(rest_after_keyword(line));
    } else if (kw == "format") {
      if (has_format) bad("second 'format' line");
      if (words.size() != 3) bad(fmt::format("bad format line '{}'", io::echo(line)));
      if (words[1] == "ascii")
        h.encoding = Encoding::ascii;
      else if (words[1] == "binary_little_endian")
        h.encoding = Encoding::binary_little_endian;
      else if (words[1] == "binary_big_endian")
        h.encoding = Encoding::binary_big_endian;
      else
        bad(fmt::format("unknown format '{}'", io::echo(words[1])));
      if (words[2] != "1.0" && words[2] != "1") bad(fmt::format("unsupported PLY format version '{}'", io::echo(words[2])));
      has_format = true;
    } else if (kw == "element") {
      if (words.size() != 3) bad(fmt::format("bad element line '{}'", io::echo(line)));
      Element e;
      e.name = std::string(words[1]);
      if (h.find(e.name)) bad(fmt::format("element '{}' declared twice", io::echo(e.name)));
      const std::string_view c = words[2];
      if (c.starts_with('-')) bad(fmt::format("element '{}': count {} is negative", io::echo(e.name), io::echo(c)));
      const auto [end, ec] = std::from_chars(c.data(), c.data() + c.size(), e.count);
      if (ec == std::errc::result_out_of_range) bad(fmt::format("element '{}': count {} is absurd", io::echo(e.name), io::echo(c)));
      if (ec != std::errc() || end != c.data() + c.size())
        bad(fmt::format("element '{}': count '{}' is not a non-negative integer", io::echo(e.name), io::echo(c)));
      h.elements.push_back(std::move(e));
    } else if (kw == "property") {
      if (h.elements.empty()) bad("property before any element");
      Element& e = h.elements.back();
      Property p;
      if (words.size() >= 2 && words[1] == "list") {
        if (words.size() != 5) bad(fmt::format("element '{}': bad list property line '{}'", io::echo(e.name), io::echo(line)));
        if (!parse_type(words[2], p.count_type))
          bad(fmt::format("element '{}': unknown type '{}' of property '{}'", io::echo(e.name), io::echo(words[2]), io::echo(words[4])));
        if (!parse_type(words[3], p.type))
          bad(fmt::format("element '{}': unknown type '{}' of property '{}'", io::echo(e.name), io::echo(words[3]), io::echo(words[4])));
        if (!is_integer_type(p.count_type))
          bad(fmt::format("element '{}': list count type of property '{}' must be an integer type", io::echo(e.name), io::echo(words[4])));
        p.is_list = true;
        p.name = std::string(words[4]);
      } else {
        if (words.size() != 3) bad(fmt::format("element '{}': bad property line '{}'", io::echo(e.name), io::echo(line)));
        if (!parse_type(words[1], p.type))
          bad(fmt::format("element '{}': unknown type '{}' of property '{}'", io::echo(e.name), io::echo(words[1]), io::echo(words[2])));
        p.name = std::string(words[2]);
      }
      if (e.find(p.name) >= 0) bad(fmt::format("element '{}': property '{}' declared twice", io::echo(e.name), io::echo(p.name)));
      e.properties.push_back(std::move(p));
    } else {
      bad(fmt::format("unknown keyword '{}'", io::echo(kw)));
    }
  }
  if (!has_format) fail(pos, "no 'format' line in the header");
  h.body_offset = pos;
  return f;
}

std::vector<Table> File::read(std::span<const Request> requests) const {
  const std::string_view s = bytes_;
  const Header& h = header_;
  const bool ascii = h.encoding == Encoding::ascii;
  const bool swap = h.encoding == Encoding::binary_big_endian;

  // Per element: the request it serves (or −1) and, per property, its column (or −1).
  std::vector<int> element_request(h.elements.size(), -1);
  std::vector<std::vector<int>> column(h.elements.size());
  std::vector<Table> tables(requests.size());
  // Per element and property: which returned list it fills (0: Table::list, k > 0: more_lists[k − 1]) or −1.
  std::vector<std::vector<int>> list_slot(h.elements.size());
  for (std::size_t r = 0; r < requests.size(); ++r) {
    const Request& req = requests[r];
    const auto it =
        std::find_if(h.elements.begin(), h.elements.end(), [&](const Element& e) { return e.name == req.element; });
    if (it == h.elements.end())
      throw FormatError(message({}, -1, {}, kNoByte, fmt::format("no element '{}' in the header", req.element)));
    const std::size_t ei = static_cast<std::size_t>(it - h.elements.begin());
    element_request[ei] = static_cast<int>(r);
    column[ei].assign(it->properties.size(), -1);
    for (std::size_t c = 0; c < req.properties.size(); ++c) {
      const int pi = it->find(req.properties[c]);
      if (pi < 0)
        throw FormatError(
            message(it->name, -1, req.properties[c], kNoByte, "required property is missing from the header"));
      if (it->properties[pi].is_list)
        throw FormatError(message(it->name, -1, req.properties[c], kNoByte, "is a list where a scalar is required"));
      column[ei][pi] = static_cast<int>(c);
    }
    tables[r].element = it->name;
    tables[r].properties = req.properties;
    list_slot[ei].assign(it->properties.size(), -1);
    const auto want_list = [&](const std::string& name, int slot) {
      const int pi = it->find(name);
      if (pi < 0)
        throw FormatError(message(it->name, -1, name, kNoByte, "required property is missing from the header"));
      if (!it->properties[pi].is_list)
        throw FormatError(message(it->name, -1, name, kNoByte, "is a scalar where a list is required"));
      list_slot[ei][pi] = slot;
    };
    if (!req.list.empty()) {
      want_list(req.list, 0);
      tables[r].list = req.list;
    }
    for (std::size_t k = 0; k < req.more_lists.size(); ++k) {
      want_list(req.more_lists[k], static_cast<int>(k) + 1);
      tables[r].more_lists.push_back({req.more_lists[k], {0}, {}});
    }
  }

  std::size_t pos = h.body_offset;
  for (std::size_t ei = 0; ei < h.elements.size(); ++ei) {
    const Element& e = h.elements[ei];
    const std::size_t remaining = s.size() - pos;
    Table* table = element_request[ei] >= 0 ? &tables[element_request[ei]] : nullptr;
    const std::size_t ncols = table ? table->properties.size() : 0;
    const std::vector<int>& col = column[ei];
    // Where list property pi's kept entries go (nullptr: not kept), and the end of a row's lists.
    const auto list_values = [&](std::size_t pi) -> std::vector<double>* {
      if (!table || list_slot[ei][pi] < 0) return nullptr;
      return list_slot[ei][pi] == 0 ? &table->list_values : &table->more_lists[list_slot[ei][pi] - 1].values;
    };
    const auto end_row_lists = [&] {
      if (!table) return;
      if (!table->list.empty()) table->list_offsets.push_back(table->list_values.size());
      for (auto& l : table->more_lists) l.offsets.push_back(l.values.size());
    };

    // Validate the count against the bytes left before allocating anything.
    std::size_t min_row = 0;
    bool fixed = true;
    for (const auto& p : e.properties) {
      if (ascii)
        min_row += 2;
      else
        min_row += p.is_list ? type_size(p.count_type) : type_size(p.type);
      fixed = fixed && !p.is_list;
    }
    if (e.count > 0 && min_row == 0)
      throw FormatError(
          message(e.name, -1, {}, pos, fmt::format("{} rows declared but the element has no properties", e.count)));
    const std::size_t budget = ascii ? remaining + 1 : remaining;  // the last ASCII value may lack a newline
    if (e.count > 0 && e.count > budget / min_row) {
      throw FormatError(message(
          e.name, static_cast<std::int64_t>(budget / min_row), {}, pos + (budget / min_row) * (ascii ? 0 : min_row),
          fmt::format("count {} exceeds the file (truncated file or bad count): each row needs at least {} bytes, "
                      "only {} bytes are left",
                      e.count, min_row, remaining)));
    }

    if (table) {
      table->rows = e.count;
      table->values.resize(e.count * ncols);
      table->row_offsets.resize(e.count);
      table->column_offsets.assign(ncols, -1);
      if (!table->list.empty()) table->list_offsets.assign(1, 0);
      if (!ascii) {
        std::int64_t off = 0;
        for (std::size_t pi = 0; pi < e.properties.size(); ++pi) {
          if (e.properties[pi].is_list) break;
          if (col[pi] >= 0) table->column_offsets[col[pi]] = off;
          off += static_cast<std::int64_t>(type_size(e.properties[pi].type));
        }
      }
    }

    if (!ascii) {
      for (std::uint64_t row = 0; row < e.count; ++row) {
        if (table) table->row_offsets[row] = pos;
        double* out = table ? table->values.data() + row * ncols : nullptr;
        for (std::size_t pi = 0; pi < e.properties.size(); ++pi) {
          const Property& p = e.properties[pi];
          if (!p.is_list) {
            const std::size_t n = type_size(p.type);
            if (n > s.size() - pos)
              throw FormatError(
                  message(e.name, static_cast<std::int64_t>(row), p.name, pos, "truncated: unexpected end of file"));
            if (out && col[pi] >= 0) out[col[pi]] = load_value(s.data() + pos, p.type, swap);
            pos += n;
            continue;
          }
          const std::size_t cn = type_size(p.count_type);
          if (cn > s.size() - pos)
            throw FormatError(
                message(e.name, static_cast<std::int64_t>(row), p.name, pos, "truncated: unexpected end of file"));
          const double count = load_value(s.data() + pos, p.count_type, swap);
          if (count < 0)
            throw FormatError(message(e.name, static_cast<std::int64_t>(row), p.name, pos,
                                      fmt::format("list count {} is negative", count)));
          const std::size_t vn = type_size(p.type);
          const std::size_t left = s.size() - pos - cn;
          if (count > static_cast<double>(left / vn))
            throw FormatError(message(e.name, static_cast<std::int64_t>(row), p.name, pos,
                                      fmt::format("truncated: list count {} needs {} bytes but only {} are left", count,
                                                  count * static_cast<double>(vn), left)));
          if (std::vector<double>* keep = list_values(pi))
            for (std::size_t k = 0; k < static_cast<std::size_t>(count); ++k)
              keep->push_back(load_value(s.data() + pos + cn + k * vn, p.type, swap));
          pos += cn + static_cast<std::size_t>(count) * vn;
        }
        end_row_lists();
      }
      continue;
    }

    // ASCII: one row per line, values separated by blanks.
    for (std::uint64_t row = 0; row < e.count; ++row) {
      while (pos < s.size() && (is_blank(s[pos]) || s[pos] == '\n')) ++pos;  // blank lines
      const std::size_t row_start = pos;
      if (table) table->row_offsets[row] = row_start;
      double* out = table ? table->values.data() + row * ncols : nullptr;
      auto next_value = [&](const Property& p, Type t, std::string_view what) -> double {
        while (pos < s.size() && is_blank(s[pos])) ++pos;
        if (pos >= s.size())
          throw FormatError(message(e.name, static_cast<std::int64_t>(row), p.name, pos,
                                    fmt::format("truncated: unexpected end of file where {} was expected", what)));
        if (s[pos] == '\n')
          throw FormatError(message(e.name, static_cast<std::int64_t>(row), p.name, pos,
                                    fmt::format("too few values on the line ({} expected)", what)));
        const std::size_t start = pos;
        while (pos < s.size() && !is_blank(s[pos]) && s[pos] != '\n') ++pos;
        std::string_view tok = s.substr(start, pos - start);
        std::string_view num = tok.starts_with('+') ? tok.substr(1) : tok;
        double v = 0.0;
        const auto [end, ec] = std::from_chars(num.data(), num.data() + num.size(), v);
        if (ec != std::errc() || end != num.data() + num.size() || num.empty())
          throw FormatError(
              message(e.name, static_cast<std::int64_t>(row), p.name, start, fmt::format("'{}' is not a number", io::echo(tok))));
        if (is_integer_type(t) && (v != std::floor(v) || v < type_min(t) || v > type_max(t)))
          throw FormatError(message(e.name, static_cast<std::int64_t>(row), p.name, start,
                                    fmt::format("'{}' is not a valid {} value", io::echo(tok), type_name(t))));
        return v;
      };
      for (std::size_t pi = 0; pi < e.properties.size(); ++pi) {
        const Property& p = e.properties[pi];
        if (!p.is_list) {
          const double v = next_value(p, p.type, "a value");
          if (out && col[pi] >= 0) out[col[pi]] = v;
          continue;
        }
        const std::size_t count_at = pos;
        const double count = next_value(p, p.count_type, "a list count");
        if (count < 0)
          throw FormatError(message(e.name, static_cast<std::int64_t>(row), p.name, count_at,
                                    fmt::format("list count {} is negative", count)));
        if (count > static_cast<double>((s.size() - pos) / 2 + 1))
          throw FormatError(message(e.name, static_cast<std::int64_t>(row), p.name, count_at,
                                    fmt::format("truncated: list count {} exceeds the rest of the file", count)));
        std::vector<double>* keep = list_values(pi);
        for (std::uint64_t k = 0; k < static_cast<std::uint64_t>(count); ++k) {
          const double v = next_value(p, p.type, "a list entry");
          if (keep) keep->push_back(v);
        }
      }
      end_row_lists();
      while (pos < s.size() && is_blank(s[pos])) ++pos;
      if (pos < s.size() && s[pos] != '\n') {
        std::size_t end = pos;
        while (end < s.size() && !is_blank(s[end]) && s[end] != '\n') ++end;
        throw FormatError(
            message(e.name, static_cast<std::int64_t>(row), {}, pos,
                    fmt::format("extra value '{}' at the end of the row ({} properties declared)",
                                io::echo(s.substr(pos, std::min<std::size_t>(end - pos, 40))), e.properties.size())));
      }
      if (pos < s.size()) ++pos;
    }
  }
  // Bytes after the declared rows: a wrong count or a wrong encoding, never silently ignored.
  if (ascii)
    while (pos < s.size() && (is_blank(s[pos]) || s[pos] == '\n')) ++pos;
  if (pos < s.size())
    throw FormatError(message({}, -1, {}, pos,
                              fmt::format("{} bytes of trailing data after the declared elements (a count too small, "
                                          "or a body in another encoding than the header's '{}'?)",
                                          s.size() - pos, ascii ? "ascii" : swap ? "binary_big_endian" : "binary_little_endian")));
  return tables;
}

std::string header_text(const Header& header) {
  std::string out = "ply\nformat ";
  switch (header.encoding) {
    case Encoding::ascii:
      out += "ascii";
      break;
    case Encoding::binary_little_endian:
      out += "binary_little_endian";
      break;
    case Encoding::binary_big_endian:
      out += "binary_big_endian";
      break;
  }
  out += " 1.0\n";
  for (const auto& c : header.comments) out += "comment " + c + "\n";
  for (const auto& c : header.obj_info) out += "obj_info " + c + "\n";
  for (const auto& e : header.elements) {
    out += fmt::format("element {} {}\n", e.name, e.count);
    for (const auto& p : e.properties) {
      if (p.is_list)
        out += fmt::format("property list {} {} {}\n", type_name(p.count_type), type_name(p.type), p.name);
      else
        out += fmt::format("property {} {}\n", type_name(p.type), p.name);
    }
  }
  out += "end_header\n";
  return out;
}

void append_le(std::string& out, Type t, double v) {
  char buf[8];
  auto put = [&](auto x) {
    std::memcpy(buf, &x, sizeof(x));
    out.append(buf, sizeof(x));
  };
  switch (t) {
    case Type::int8:
      put(static_cast<std::int8_t>(std::lround(v)));
      break;
    case Type::uint8:
      put(static_cast<std::uint8_t>(std::lround(v)));
      break;
    case Type::int16:
      put(static_cast<std::int16_t>(std::lround(v)));
      break;
    case Type::uint16:
      put(static_cast<std::uint16_t>(std::lround(v)));
      break;
    case Type::int32:
      put(static_cast<std::int32_t>(std::llround(v)));
      break;
    case Type::uint32:
      put(static_cast<std::uint32_t>(std::llround(v)));
      break;
    case Type::float32:
      put(static_cast<float>(v));
      break;
    case Type::float64:
      put(v);
      break;
  }
}

}  // namespace quadrix::ply
