// Places in a JSON file's text, for errors a person fixes in an editor: why a text is not JSON
// and where, which value a place falls in, and where a value is. nlohmann::json's parse errors
// carry a byte offset and its values none, so readers that name "line 4, column 17" come here.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace afterglow {

// A value's place in its document: object keys (as written between the quotes) and array
// indices (decimal), outermost first. {"positions", "2"} is the third entry of "positions".
using JsonPath = std::vector<std::string>;

// "line L, column C" of byte `offset` of text, both from 1, columns in bytes (as nlohmann::json
// and compilers count them).
std::string textPlace(const std::string& text, size_t offset);

// Why text is not JSON, as nlohmann::json reads it (numbers beyond a double's range refused),
// and where: the byte that broke the grammar, or the start of a number out of range.
struct JsonSyntaxError {
  size_t offset = 0;
  std::string reason;  // nlohmann's words, without its exception id and position
};
std::optional<JsonSyntaxError> findJsonSyntaxError(const std::string& text);

// Where the value at `path` starts in text (JSON, valid at least that far); when part of the
// path is not there, where the deepest part that is starts.
size_t jsonValueOffset(const std::string& text, const JsonPath& path);
// Where `offset` is (text valid JSON up to there): the entry of each container around it that
// it is in or after, as a syntax error at offset is in the entry it breaks ("[1, 2, ]" breaks
// entry 2).
JsonPath jsonPathAt(const std::string& text, size_t offset);

}  // namespace afterglow
