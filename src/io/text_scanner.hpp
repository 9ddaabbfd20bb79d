#pragma once
// Whitespace-separated tokens from an in-memory text file, with the line number of each token so
// that every parse error can name file and line.

#include <tetcut/error.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace tetcut::io {

class TextScanner {
 public:
  /// `comment` starts a comment that runs to the end of the line; '\0' means the format has none.
  TextScanner(std::string_view text, std::string source, char comment = '#');

  /// Skips whitespace and comments; true when no token is left.
  bool at_end();
  /// The next token, or nullopt at the end of the text.
  std::optional<std::string_view> try_token();
  /// The next token; at the end of the text, fails with "unexpected end of file, expected <what>".
  std::string_view token(std::string_view what);
  /// The next token as a finite double.
  double real(std::string_view what);
  /// The next token as an integer.
  std::int64_t integer(std::string_view what);
  /// The next token as an integer in [lo, hi].
  std::int64_t integer_in(std::string_view what, std::int64_t lo, std::int64_t hi);
  /// Expects the next token to equal `keyword` (case-sensitive).
  void expect(std::string_view keyword);
  /// The rest of the current line (after the last token read), and moves to the next line.
  std::string_view rest_of_line();
  /// Byte offset just after the last token or line read.
  std::size_t offset() const { return pos_; }
  /// Jumps to a byte offset (past binary data); line numbers after a jump count from there.
  void seek(std::size_t offset) { pos_ = offset; }

  /// Line of the last token returned (1-based).
  std::int64_t line() const { return token_line_; }
  const std::string& source() const { return source_; }
  [[noreturn]] void fail(const std::string& message) const;
  [[noreturn]] void fail_at(std::int64_t line, const std::string& message) const;

 private:
  void skip_space();

  std::string_view text_;
  std::string source_;
  char comment_;
  std::size_t pos_ = 0;
  std::int64_t line_ = 1;        // line at pos_
  std::int64_t token_line_ = 1;  // line of the last token
};

/// True when `text` holds only spaces and tabs.
bool is_blank(std::string_view text);

/// Parses a whole token as a double / integer; nullopt when the token is not one. No locale.
std::optional<double> parse_real(std::string_view token);
std::optional<std::int64_t> parse_integer(std::string_view token);

}  // namespace tetcut::io
