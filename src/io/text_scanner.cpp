#include "io/text_scanner.hpp"

#include <charconv>
#include <cmath>
#include <utility>

namespace tetcut::io {

bool is_blank(std::string_view text) {
  return text.find_first_not_of(" \t\r") == std::string_view::npos;
}

std::optional<double> parse_real(std::string_view token) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  double value = 0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec != std::errc() || end != token.data() + token.size()) return std::nullopt;
  return value;
}

std::optional<std::int64_t> parse_integer(std::string_view token) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  std::int64_t value = 0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec != std::errc() || end != token.data() + token.size()) return std::nullopt;
  return value;
}

TextScanner::TextScanner(std::string_view text, std::string source, char comment)
    : text_(text), source_(std::move(source)), comment_(comment) {}

void TextScanner::skip_space() {
  while (pos_ < text_.size()) {
    const char c = text_[pos_];
    if (c == '\n') {
      ++line_;
      ++pos_;
    } else if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
      ++pos_;
    } else if (comment_ != '\0' && c == comment_) {
      while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
    } else {
      return;
    }
  }
}

bool TextScanner::at_end() {
  skip_space();
  return pos_ >= text_.size();
}

std::optional<std::string_view> TextScanner::try_token() {
  skip_space();
  if (pos_ >= text_.size()) return std::nullopt;
  const std::size_t start = pos_;
  while (pos_ < text_.size()) {
    const char c = text_[pos_];
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v') break;
    if (comment_ != '\0' && c == comment_) break;
    ++pos_;
  }
  token_line_ = line_;
  return text_.substr(start, pos_ - start);
}

std::string_view TextScanner::token(std::string_view what) {
  const auto t = try_token();
  // Report the line of the last token: the trailing newline would otherwise name a line past the data.
  if (!t) fail("unexpected end of file, expected " + std::string(what));
  return *t;
}

double TextScanner::real(std::string_view what) {
  const std::string_view t = token(what);
  const auto value = parse_real(t);
  if (!value) fail("expected " + std::string(what) + " (a number), found '" + std::string(t) + "'");
  if (!std::isfinite(*value)) fail(std::string(what) + " is not a finite number ('" + std::string(t) + "')");
  return *value;
}

std::int64_t TextScanner::integer(std::string_view what) {
  const std::string_view t = token(what);
  const auto value = parse_integer(t);
  if (!value) fail("expected " + std::string(what) + " (an integer), found '" + std::string(t) + "'");
  return *value;
}

std::int64_t TextScanner::integer_in(std::string_view what, std::int64_t lo, std::int64_t hi) {
  const std::int64_t value = integer(what);
  if (value < lo || value > hi) {
    fail(std::string(what) + " " + std::to_string(value) + " is out of range [" + std::to_string(lo) + ", " +
         std::to_string(hi) + "]");
  }
  return value;
}

void TextScanner::expect(std::string_view keyword) {
  const std::string_view t = token(keyword);
  if (t != keyword) fail("expected '" + std::string(keyword) + "', found '" + std::string(t) + "'");
}

std::string_view TextScanner::rest_of_line() {
  const std::size_t start = pos_;
  while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
  std::string_view rest = text_.substr(start, pos_ - start);
  token_line_ = line_;
  if (pos_ < text_.size()) {
    ++pos_;
    ++line_;
  }
  if (!rest.empty() && rest.back() == '\r') rest.remove_suffix(1);
  return rest;
}

void TextScanner::fail(const std::string& message) const { fail_at(token_line_, message); }

void TextScanner::fail_at(std::int64_t line, const std::string& message) const {
  throw Error(ErrorKind::kInvalidInput, message, source_, line);
}

}  // namespace tetcut::io
