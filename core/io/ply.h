#pragma once
/// A general PLY reader (ASCII, binary little/big-endian) that returns the scalar columns the
/// caller asks for as double and skips, while still validating, every other element and
/// property (list properties included); plus the helpers that write binary little-endian PLY.
///
/// Validates before it trusts: an element's count is checked against the bytes left in the
/// file (binary: exact row size, at least the count bytes of each list; ASCII: at least two
/// bytes per value) before anything is allocated for it. Every error is a FormatError of the
/// form `FILE: element 'E' row R property 'P' at byte B: what` (the parts that apply).
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace quadrix::ply {

enum class Encoding { ascii, binary_little_endian, binary_big_endian };
enum class Type : std::uint8_t { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

/// Size in bytes of one binary value of type t.
std::size_t type_size(Type t);
/// The canonical PLY name (`char uchar short ushort int uint float double`).
std::string_view type_name(Type t);

struct Property {
  std::string name;
  Type type = Type::float64;  ///< value type (of the entries, for a list)
  bool is_list = false;
  Type count_type = Type::uint8;  ///< lists only
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
  /// Index of the property called name, or -1.
  int find(std::string_view name) const;
};

struct Header {
  Encoding encoding = Encoding::binary_little_endian;
  std::vector<std::string> comments;  ///< text after `comment `, in file order
  std::vector<std::string> obj_info;  ///< text after `obj_info `
  std::vector<Element> elements;
  std::size_t body_offset = 0;  ///< first byte after the `end_header` line
  /// The element called name, or nullptr.
  const Element* find(std::string_view name) const;
};

/// Scalar columns of one element: rows × properties.size() doubles, row-major.
struct Table {
  std::string element;
  std::vector<std::string> properties;
  std::size_t rows = 0;
  std::vector<double> values;
  std::vector<std::uint64_t> row_offsets;    ///< byte offset in the file where each row starts
  std::vector<std::int64_t> column_offsets;  ///< byte offset of a column within a binary row, or −1
  std::string list;                          ///< the requested list property, or empty
  std::vector<std::uint64_t> list_offsets;   ///< row r's list entries: list_values[list_offsets[r] .. [r+1])
  std::vector<double> list_values;
  /// Further list properties (Request::more_lists), in request order; same layout as list_*.
  struct List {
    std::string name;
    std::vector<std::uint64_t> offsets;  ///< row r's entries: values[offsets[r] .. [r+1])
    std::vector<double> values;
  };
  std::vector<List> more_lists;
  double operator()(std::size_t row, std::size_t col) const { return values[row * properties.size() + col]; }
  /// Byte offset of one value (its row's start where the column offset is not fixed).
  std::uint64_t byte_offset(std::size_t row, std::size_t col) const;
};

/// File::message's byte for faults that have no byte position (e.g. a property missing from the header).
inline constexpr std::uint64_t kNoByte = ~std::uint64_t{0};

/// Which scalar properties to read from which element.
struct Request {
  std::string element;
  std::vector<std::string> properties;
  std::string list;  ///< optional: one list property whose entries are returned too
  std::vector<std::string> more_lists{};  ///< optional: further list properties (Table::more_lists)
};

/// A PLY file read into memory and its parsed header.
class File {
public:
  /// Reads the whole file and parses the header.
  /// \throws IoError when it cannot be read; FormatError for a bad magic, format line,
  ///         keyword, type, count (negative, not a number) or a missing `end_header`.
  static File open(const std::filesystem::path& path);
  /// Parses bytes as if read from path (path is used in messages only).
  static File from_bytes(std::string bytes, const std::filesystem::path& path);

  const Header& header() const { return header_; }
  const std::filesystem::path& path() const { return path_; }
  std::size_t size() const { return bytes_.size(); }

  /// Walks the whole body once; returns one Table per request, in request order.
  /// \throws FormatError when a requested element or property is missing or is a list,
  ///         a count exceeds the file, the file is truncated, a token is not a number or out
  ///         of its type's range, a list count is negative or exceeds the file, or bytes
  ///         follow the last declared row (ASCII: anything but whitespace).
  std::vector<Table> read(std::span<const Request> requests) const;

  /// `FILE: element 'E' row R property 'P' at byte B: what` (empty E or P, row < 0 and
  /// byte == kNoByte are left out).
  std::string message(std::string_view element, std::int64_t row, std::string_view property, std::uint64_t byte,
                      std::string_view what) const;

private:
  std::filesystem::path path_;
  std::string bytes_;
  Header header_;
};

/// The header text of a PLY file (`ply` … `end_header\n`); elements with their counts.
std::string header_text(const Header& header);

/// Appends v converted to t as binary little-endian (integers are rounded).
void append_le(std::string& out, Type t, double v);

}  // namespace quadrix::ply
