#pragma once
/// @file
/// Text from users' files, made safe to write: names in a Latin-1 file (`Größe`) are not
/// UTF-8, and JSON, XML and the terminal refuse or garble them; and how close a mistyped name
/// is to a known one.

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace hof {

/// `text` with every byte that does not start a well-formed UTF-8 sequence replaced by
/// U+FFFD (the replacement character); valid text is returned unchanged.
[[nodiscard]] std::string valid_utf8(std::string_view text);

/// `text` without its leading and trailing ASCII white space (space, tab, CR, LF, FF, VT).
[[nodiscard]] constexpr std::string_view trim_whitespace(std::string_view text) {
  constexpr std::string_view kWhitespace = " \t\r\n\f\v";
  const auto first = text.find_first_not_of(kWhitespace);
  if (first == std::string_view::npos) return {};
  return text.substr(first, text.find_last_not_of(kWhitespace) - first + 1);
}

/// The blank-separated words of one line (blanks: space, tab, CR), in order: the tokens of the
/// line-oriented text formats (SOFA's legacy files, `.sph`).
[[nodiscard]] std::vector<std::string_view> blank_separated_words(std::string_view line);

/// Edits (insert, delete or substitute a letter, ASCII case ignored) that turn `a` into `b`
/// (Levenshtein distance): how close a mistyped name is to a known one.
[[nodiscard]] std::size_t edit_distance(std::string_view a, std::string_view b);

}  // namespace hof
