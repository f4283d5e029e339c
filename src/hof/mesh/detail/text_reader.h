#pragma once
/// @file
/// Internal helpers shared by the mesh readers and writers (hof::mesh::detail, not API):
/// strict number parsing with std::from_chars, a token Scanner and a LineReader that count
/// lines so every Error can name FILE:LINE, guards that check counts read from a file
/// against the bytes left before anything is reserved, and number formatting that round-trips.
///
/// The Scanner latches its first error: after a failure every further read returns 0 and
/// does nothing, so a reader can parse a whole record and check `failed()` once per record.

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <string_view>
#include <system_error>

#include "hof/core/error.h"
#include "hof/mesh/mesh.h"

namespace hof::mesh::detail {

// ---------------------------------------------------------------------------------------
// Files (defined in mesh_io.cpp)

/// Reads the whole file into memory. kIo naming the file when it is missing, a directory
/// or unreadable.
[[nodiscard]] Expected<std::string> read_whole_file(const std::filesystem::path& path);

/// Replaces the file's content by `bytes`. kIo naming the file on any failure.
[[nodiscard]] Expected<void> write_whole_file(const std::filesystem::path& path, std::string_view bytes);

/// Checks a mesh before writing: at least one node, finite coordinates, element indices in
/// range, region and normal arrays empty or of matching length. kInvalidArgument naming the
/// file about to be written.
[[nodiscard]] Expected<void> check_mesh_for_write(const Mesh& mesh, const std::filesystem::path& path);

// ---------------------------------------------------------------------------------------
// Characters and tokens

/// Whitespace as the text formats understand it (NUL is deliberately not whitespace, so
/// binary garbage fails to parse instead of vanishing).
[[nodiscard]] constexpr bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

/// ASCII case-insensitive equality (format keywords such as `solid`, `$EndNodes`).
[[nodiscard]] inline bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const auto lower = [](char c) { return c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c; };
    if (lower(a[i]) != lower(b[i])) return false;
  }
  return true;
}

/// Whether the text holds nothing but whitespace (an "empty" file for text formats).
[[nodiscard]] inline bool is_blank(std::string_view text) {
  return std::all_of(text.begin(), text.end(), [](char c) { return is_space(c); });
}

/// A token for an error message: quoted, non-printable bytes as \xNN, long tokens cut, so a
/// message about binary garbage stays one readable line.
[[nodiscard]] inline std::string quoted(std::string_view token) {
  constexpr std::size_t kMaxShown = 40;
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out = "'";
  for (std::size_t i = 0; i < token.size() && i < kMaxShown; ++i) {
    const auto c = static_cast<unsigned char>(token[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 0xf];
    }
  }
  if (token.size() > kMaxShown) out += "...";
  out += '\'';
  return out;
}

// ---------------------------------------------------------------------------------------
// Numbers

/// Parses all of `token` as a decimal integer with an optional sign. False when any byte is
/// left over or the value does not fit in int64.
[[nodiscard]] inline bool parse_int(std::string_view token, std::int64_t& out) {
  if (!token.empty() && token.front() == '+') {
    token.remove_prefix(1);
    if (token.empty() || token.front() == '-') return false;
  }
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, out);
  return ec == std::errc{} && ptr == end && !token.empty();
}

/// Outcome of parse_real: a number, not a number at all, or a number that is NaN/infinite
/// (the latter is an invalid mesh rather than a parse error).
enum class RealParse : std::uint8_t { kOk, kNotANumber, kNotFinite };

/// Parses all of `token` as a decimal floating-point number (optional sign, exponent).
[[nodiscard]] inline RealParse parse_real(std::string_view token, double& out) {
  if (!token.empty() && token.front() == '+') {
    token.remove_prefix(1);
    if (token.empty() || token.front() == '-') return RealParse::kNotANumber;
  }
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, out, std::chars_format::general);
  if (ptr != end || token.empty()) return RealParse::kNotANumber;
  if (ec == std::errc::result_out_of_range) {
    // from_chars also flags underflow (1e-400) without giving a value; strtod turns that
    // into 0 (or a subnormal) and overflow into ±HUGE_VAL, which is then rejected below.
    // The token is well-formed here, so strtod consumes exactly what from_chars matched.
    const std::string copy(token);
    out = std::strtod(copy.c_str(), nullptr);
  } else if (ec != std::errc{}) {
    return RealParse::kNotANumber;
  }
  return std::isfinite(out) ? RealParse::kOk : RealParse::kNotFinite;
}

/// Appends the shortest decimal text that reads back as exactly `value` (std::to_chars
/// round-trip guarantee), so write → read reproduces every coordinate bit for bit.
inline void append_real(std::string& out, double value) {
  std::array<char, 32> buffer{};
  const auto [ptr, ec] = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  out.append(buffer.data(), ec == std::errc{} ? static_cast<std::size_t>(ptr - buffer.data()) : 0);
}

/// Appends a decimal integer.
inline void append_int(std::string& out, std::int64_t value) {
  std::array<char, 24> buffer{};
  const auto [ptr, ec] = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  out.append(buffer.data(), ec == std::errc{} ? static_cast<std::size_t>(ptr - buffer.data()) : 0);
}

/// Whether `count` records of at least `min_bytes` each can be stored in `bytes_left`
/// bytes. Every count read from a file passes this before it sizes an allocation, so a
/// corrupt count fails at once instead of reserving gigabytes.
[[nodiscard]] inline bool count_fits(std::int64_t count, std::int64_t min_bytes, std::size_t bytes_left) {
  return count >= 0 && count <= static_cast<std::int64_t>(bytes_left) / min_bytes;
}

/// The message for a count that fails count_fits.
[[nodiscard]] inline std::string impossible_count(const std::string& what, std::int64_t count, std::int64_t min_bytes,
                                                  std::size_t bytes_left) {
  std::string message = what + " " + std::to_string(count) + " is impossible: ";
  if (count < 0) return message + "it is negative";
  return message + "it needs more than the " + std::to_string(bytes_left) + " bytes left in the file (at least " +
         std::to_string(min_bytes) + " per entry); the file is truncated or the count is wrong";
}

/// Error for a binary file: byte offset instead of a line.
[[nodiscard]] inline std::unexpected<Error> make_byte_error(ErrorCode code, std::string message, std::string file,
                                                            std::int64_t byte_offset) {
  return std::unexpected<Error>(Error{code, std::move(message), std::move(file), 0, byte_offset});
}

// ---------------------------------------------------------------------------------------
// Scanner: whitespace-separated tokens over an in-memory text, with line numbers

/// Tokens of a text in order, tracking the 1-based line of the last token. An optional
/// comment character starts a comment that runs to the end of the line. In binary mode
/// errors carry the token's byte offset instead of a line (for Gmsh binary files, whose
/// binary blocks make line numbers meaningless).
class Scanner {
 public:
  Scanner(std::string_view text, std::string file, char comment = '\0', std::int64_t first_line = 1,
          std::int64_t base_offset = 0)
      : text_(text),
        file_(std::move(file)),
        comment_(comment),
        line_(first_line),
        token_line_(first_line),
        first_line_(first_line),
        base_offset_(base_offset) {}

  /// The next token, or an empty view at the end of the text.
  std::string_view next() {
    skip_space();
    token_line_ = line_;
    token_start_ = pos_;
    while (pos_ < text_.size() && !is_space(text_[pos_])) ++pos_;
    if (token_start_ == text_.size()) {
      // At the end, name the last line that has content, not the empty one after it.
      std::int64_t trailing_newlines = 0;
      for (std::size_t p = text_.size(); p > 0 && is_space(text_[p - 1]); --p) {
        if (text_[p - 1] == '\n') ++trailing_newlines;
      }
      token_line_ = std::max<std::int64_t>(first_line_, line_ - trailing_newlines);
    }
    return text_.substr(token_start_, pos_ - token_start_);
  }

  /// The next token without consuming it.
  [[nodiscard]] std::string_view peek() {
    Scanner copy = *this;
    return copy.next();
  }

  /// Whether only whitespace and comments are left.
  [[nodiscard]] bool at_end() {
    skip_space();
    return pos_ >= text_.size();
  }

  /// Whether the current line holds another token (before its newline).
  [[nodiscard]] bool line_has_more() const {
    for (std::size_t p = pos_; p < text_.size(); ++p) {
      const char c = text_[p];
      if (c == '\n' || (comment_ != '\0' && c == comment_)) return false;
      if (!is_space(c)) return true;
    }
    return false;
  }

  /// Skips the rest of the current line, including its newline.
  void skip_line() {
    while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
    if (pos_ < text_.size()) {
      ++pos_;
      ++line_;
    }
  }

  /// The next token as an integer; on failure latches an error naming `what`.
  std::int64_t integer(std::string_view what) {
    if (failed_) return 0;
    const std::string_view token = next();
    std::int64_t value = 0;
    if (!parse_int(token, value)) {
      fail_token(token, what, "an integer");
      return 0;
    }
    return value;
  }

  /// The next token as a finite real; NaN or infinity latches kInvalidMesh.
  double real(std::string_view what) {
    if (failed_) return 0.0;
    const std::string_view token = next();
    double value = 0.0;
    switch (parse_real(token, value)) {
      case RealParse::kOk:
        return value;
      case RealParse::kNotFinite:
        fail(ErrorCode::kInvalidMesh, std::string(what) + " is " + quoted(token) + ", not a finite number");
        return 0.0;
      case RealParse::kNotANumber:
        break;
    }
    fail_token(token, what, "a number");
    return 0.0;
  }

  /// Consumes the next token and checks it equals `keyword` (ASCII case-insensitive).
  void expect(std::string_view keyword) {
    if (failed_) return;
    const std::string_view token = next();
    if (!iequals(token, keyword)) fail_token(token, std::string("'") + std::string(keyword) + "'", "");
  }

  /// Latches an error at the last token.
  void fail(ErrorCode code, std::string message) {
    if (failed_) return;
    failed_ = true;
    error_ = Error{code, std::move(message), file_, binary_ ? 0 : token_line_,
                   binary_ ? base_offset_ + static_cast<std::int64_t>(token_start_) : -1};
  }

  /// Latches an error at a byte offset (binary blocks).
  void fail_at_byte(ErrorCode code, std::string message, std::size_t offset) {
    if (failed_) return;
    failed_ = true;
    error_ = Error{code, std::move(message), file_, 0, base_offset_ + static_cast<std::int64_t>(offset)};
  }

  /// Adds where in the file's structure the error happened, e.g. "(node 5 of 6 in $Nodes)".
  void add_context(const std::string& context) {
    if (failed_) error_.message += " (" + context + ")";
  }

  [[nodiscard]] bool failed() const { return failed_; }
  [[nodiscard]] const Error& error() const { return error_; }
  [[nodiscard]] std::unexpected<Error> unexpected_error() const { return std::unexpected<Error>(error_); }

  [[nodiscard]] const std::string& file() const { return file_; }
  [[nodiscard]] std::string_view text() const { return text_; }
  [[nodiscard]] std::size_t pos() const { return pos_; }
  [[nodiscard]] std::size_t bytes_left() const { return text_.size() - std::min(pos_, text_.size()); }
  [[nodiscard]] std::int64_t line() const { return token_line_; }
  [[nodiscard]] std::size_t token_start() const { return token_start_; }

  /// Moves to byte `pos` (after a binary block or a skipped section); `newlines` is how many
  /// line breaks were passed, to keep line numbers right in text files.
  void jump_to(std::size_t pos, std::int64_t newlines) {
    pos_ = std::min(pos, text_.size());
    line_ += newlines;
  }

  /// Errors from now on carry byte offsets instead of lines.
  void set_binary(bool binary) { binary_ = binary; }

 private:
  void skip_space() {
    while (pos_ < text_.size()) {
      const char c = text_[pos_];
      if (c == '\n') {
        ++line_;
        ++pos_;
      } else if (is_space(c)) {
        ++pos_;
      } else if (comment_ != '\0' && c == comment_) {
        while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
      } else {
        break;
      }
    }
  }

  void fail_token(std::string_view token, std::string_view what, std::string_view kind) {
    std::string message = "expected " + std::string(what);
    if (!kind.empty()) message += " (" + std::string(kind) + ")";
    if (token.empty()) {
      message = "unexpected end of file: " + message;
    } else {
      message += ", found " + quoted(token);
    }
    fail(ErrorCode::kParse, std::move(message));
  }

  std::string_view text_;
  std::string file_;
  char comment_{'\0'};
  std::size_t pos_{0};
  std::size_t token_start_{0};
  std::int64_t line_{1};
  std::int64_t token_line_{1};
  std::int64_t first_line_{1};
  std::int64_t base_offset_{0};
  bool binary_{false};
  bool failed_{false};
  Error error_;
};

// ---------------------------------------------------------------------------------------
// LineReader: lines of a text with their numbers (for line-oriented formats such as OBJ)

/// Splits a text into lines ('\n', with a trailing '\r' removed), numbering them from 1.
class LineReader {
 public:
  explicit LineReader(std::string_view text) : text_(text) {}

  /// The next line, false at the end of the text.
  bool next(std::string_view& line) {
    if (pos_ >= text_.size()) return false;
    const std::size_t end = std::min(text_.find('\n', pos_), text_.size());
    line = text_.substr(pos_, end - pos_);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos_ = end + 1;
    ++line_number_;
    return true;
  }

  [[nodiscard]] std::int64_t line_number() const { return line_number_; }

 private:
  std::string_view text_;
  std::size_t pos_{0};
  std::int64_t line_number_{0};
};

/// Whitespace-separated tokens of one line.
class Tokens {
 public:
  explicit Tokens(std::string_view line) : rest_(line) {}

  /// The next token, or empty when the line is used up.
  std::string_view next() {
    std::size_t i = 0;
    while (i < rest_.size() && is_space(rest_[i])) ++i;
    std::size_t j = i;
    while (j < rest_.size() && !is_space(rest_[j])) ++j;
    const std::string_view token = rest_.substr(i, j - i);
    rest_.remove_prefix(j);
    return token;
  }

 private:
  std::string_view rest_;
};

}  // namespace hof::mesh::detail
