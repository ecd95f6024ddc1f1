#include "core/io/text_reader.h"

#include <algorithm>
#include <charconv>

#include "core/error.h"
#include "core/io/file.h"

namespace quadrix::io {
namespace {

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

}  // namespace

TextReader::TextReader(std::string_view text, std::filesystem::path path, char comment)
    : text_(text), path_(std::move(path)), comment_(comment) {
  // A UTF-8 byte order mark (Windows editors write one) is not part of the first token.
  if (text_.starts_with("\xEF\xBB\xBF")) next_ = 3;
  // Lines end at LF (a CR before it is a blank); a text without any LF ends them at CR (classic
  // Mac OS), so a doubled CR CR LF still counts one line.
  if (text_.find('\n') == std::string_view::npos && text_.find('\r') != std::string_view::npos) eol_ = '\r';
}

bool TextReader::next_line() {
  while (next_ < text_.size()) {
    std::size_t end = text_.find(eol_, next_);
    if (end == std::string_view::npos) end = text_.size();
    line_start_ = next_;
    line_ = text_.substr(next_, end - next_);
    next_ = end + 1;
    ++line_no_;
    if (comment_ != '\0')
      if (const auto c = line_.find(comment_); c != std::string_view::npos) line_ = line_.substr(0, c);
    col_ = token_col_ = 0;
    if (!at_line_end()) return true;
  }
  line_start_ = text_.size();
  line_ = {};
  col_ = token_col_ = 0;
  return false;
}

bool TextReader::at_line_end() {
  while (col_ < line_.size() && is_blank(line_[col_])) ++col_;
  return col_ >= line_.size();
}

std::string_view TextReader::token() {
  if (at_line_end()) {
    token_col_ = col_;
    return {};
  }
  token_col_ = col_;
  while (col_ < line_.size() && !is_blank(line_[col_])) ++col_;
  return line_.substr(token_col_, col_ - token_col_);
}

std::string_view TextReader::take(std::size_t n) {
  token_col_ = col_;
  col_ = std::min(line_.size(), col_ + n);
  return line_.substr(token_col_, col_ - token_col_);
}

std::string_view TextReader::token_across_lines() {
  while (at_line_end())
    if (!next_line()) return {};
  return token();
}

bool TextReader::parse(std::string_view tok, double& v) {
  if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
  return !tok.empty() && ec == std::errc() && ptr == tok.data() + tok.size();
}

bool TextReader::parse(std::string_view tok, long long& v) {
  if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
  return !tok.empty() && ec == std::errc() && ptr == tok.data() + tok.size();
}

double TextReader::number(std::string_view what) {
  const std::string_view tok = token();
  if (tok.empty()) fail("{}: missing (end of line)", what);
  double v = 0;
  if (!parse(tok, v)) fail("{}: '{}' is not a number", what, echo(tok));
  return v;
}

long long TextReader::integer(std::string_view what) {
  const std::string_view tok = token();
  if (tok.empty()) fail("{}: missing (end of line)", what);
  long long v = 0;
  if (!parse(tok, v)) fail("{}: '{}' is not an integer in the 64-bit range", what, echo(tok));
  return v;
}

std::string TextReader::message(std::string_view what) const {
  return text_message(path_, line_no_, token_col_ + 1, what);
}

void TextReader::fail(std::string_view what) const { throw FormatError(message(what)); }

}  // namespace quadrix::io
