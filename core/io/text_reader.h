#pragma once
/// The I/O kit's text layer: lines and blank-separated tokens of a text held in memory, with
/// `#` comments skipped and every fault reported as `FILE:LINE:COL: what` (the column of the
/// last token read). Every text reader (OFF, OBJ, STL, XYZ, Medit, TetGen, value files) uses it.
#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

#include <fmt/format.h>

namespace quadrix::io {

class TextReader {
public:
  /// text must outlive the reader; path names it in messages. comment: the character that
  /// starts a comment running to the end of the line ('\0' for none).
  TextReader(std::string_view text, std::filesystem::path path, char comment = '#');

  /// Moves to the next line holding a token; false at the end of the text.
  bool next_line();
  /// The next token of the current line; empty at its end.
  std::string_view token();
  /// The next token, moving on to following lines as needed; empty at the end of the text.
  std::string_view token_across_lines();
  /// Whether the current line has no token left.
  bool at_line_end();
  /// The current line (comment removed).
  std::string_view line() const { return line_; }
  /// The unread rest of the current line (comment removed).
  std::string_view rest_of_line() const { return line_.substr(col_); }
  /// The next n bytes of the current line (fewer at its end) as the current token, for fields
  /// that are not blank-separated (`space directions: (1,0,0) …`, `KEY=VALUE`).
  std::string_view take(std::size_t n);

  /// The next token of the line as a finite-or-not double / integer; `what` names it in the
  /// error ("vertex 3 x"): missing, not a number, or (integer) out of the int64 range.
  double number(std::string_view what);
  long long integer(std::string_view what);
  /// Parses tok; false when it is not entirely a number.
  static bool parse(std::string_view tok, double& v);
  static bool parse(std::string_view tok, long long& v);

  std::size_t line_number() const { return line_no_; }
  std::size_t column() const { return token_col_ + 1; }
  /// Bytes not yet read (the rest of the current line included).
  std::size_t bytes_left() const { return text_.size() - line_start_ - col_; }
  const std::filesystem::path& path() const { return path_; }

  /// `FILE:LINE:COL: what` at the last token read.
  std::string message(std::string_view what) const;
  [[noreturn]] void fail(std::string_view what) const;
  template <typename... Args>
  [[noreturn]] void fail(fmt::format_string<Args...> f, Args&&... args) const {
    fail(std::string_view(fmt::format(f, std::forward<Args>(args)...)));
  }

private:
  std::string_view text_;
  std::filesystem::path path_;
  char eol_ = '\n';  // '\r' for a text without any LF
  char comment_;
  std::size_t next_ = 0;        // start of the line after the current one
  std::size_t line_start_ = 0;  // start of the current line in text_
  std::string_view line_;       // the current line, comment removed
  std::size_t col_ = 0;         // read position within line_
  std::size_t token_col_ = 0;   // start of the last token within line_
  std::size_t line_no_ = 0;
};

}  // namespace quadrix::io
