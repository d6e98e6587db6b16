#include "afterglow/core/json_text.h"

#include <algorithm>

#include <nlohmann/json.hpp>

namespace afterglow {

namespace {

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }
// Not strchr: it finds a NUL byte in every string.
bool isDelimiter(char c) { return c == ',' || c == ':' || c == ']' || c == '}'; }

// Just past the string whose opening quote is at i (the text's end when it has no closing one).
size_t stringEnd(const std::string& t, size_t i) {
  for (++i; i < t.size() && t[i] != '"'; ++i)
    if (t[i] == '\\') ++i;
  return std::min(i + 1, t.size());
}

// Walks t from its start, calling visit(path, offset) at the start of each value before
// `limit` in document order until visit returns false; returns the place where it stopped: the
// containers it is in, with the entry each is at (a syntax error there is in that entry). Checks
// no grammar (nlohmann does): what it cannot place it steps over, so it also walks the valid
// beginning of a text with a syntax error.
template <class Visit>
JsonPath walkJson(const std::string& t, size_t limit, Visit visit) {
  struct Frame {
    bool object = false;
    bool wantsKey = false;
    std::string key;
    size_t index = 0;
  };
  std::vector<Frame> frames;
  auto place = [&frames] {
    JsonPath path;
    for (const Frame& f : frames)
      if (!f.wantsKey) path.push_back(f.object ? f.key : std::to_string(f.index));
    return path;
  };
  size_t i = 0;
  while (i < std::min(t.size(), limit)) {
    const char c = t[i];
    Frame* top = frames.empty() ? nullptr : &frames.back();
    if (isSpace(c) || c == ':') {
      ++i;
    } else if (c == ',') {
      if (top) top->object ? void(top->wantsKey = true) : void(++top->index);
      ++i;
    } else if (c == '}' || c == ']') {
      if (top) frames.pop_back();
      ++i;
    } else if (top && top->wantsKey) {
      const size_t end = c == '"' ? stringEnd(t, i) : i + 1;
      if (c == '"') top->key = t.substr(i + 1, std::max<size_t>(end - i, 2) - 2);
      top->wantsKey = c != '"';
      i = end;
    } else {
      if (!visit(place(), i)) break;
      if (c == '{' || c == '[') {
        frames.push_back({c == '{', c == '{', "", 0});
        ++i;
      } else if (c == '"') {
        i = stringEnd(t, i);
      } else {
        // A number or literal runs to a delimiter; anything else (a stray byte, a NUL) is one
        // character, so the walk always moves on.
        ++i;
        while (i < t.size() && !isSpace(t[i]) && !isDelimiter(t[i])) ++i;
      }
    }
  }
  return place();
}

// nlohmann's parser reports to a SAX handler where it failed; this one builds nothing.
struct SyntaxCheck : nlohmann::json::json_sax_t {
  std::optional<JsonSyntaxError> error;

  bool null() override { return true; }
  bool boolean(bool) override { return true; }
  bool number_integer(number_integer_t) override { return true; }
  bool number_unsigned(number_unsigned_t) override { return true; }
  bool number_float(number_float_t, const string_t&) override { return true; }
  bool string(string_t&) override { return true; }
  bool binary(binary_t&) override { return true; }
  bool start_object(std::size_t) override { return true; }
  bool key(string_t&) override { return true; }
  bool end_object() override { return true; }
  bool start_array(std::size_t) override { return true; }
  bool end_array() override { return true; }
  // `position` counts the bytes read, the failing one included. A number out of range (error
  // 406) was read whole: its place is its first byte.
  bool parse_error(std::size_t position, const std::string& lastToken,
                   const nlohmann::detail::exception& e) override {
    const size_t back = e.id == 406 ? lastToken.size() : 1;
    std::string reason = e.what();
    if (const size_t id = reason.find("] "); id != std::string::npos) reason.erase(0, id + 2);
    if (reason.rfind("parse error", 0) == 0)
      if (const size_t colon = reason.find(": "); colon != std::string::npos)
        reason.erase(0, colon + 2);
    error = JsonSyntaxError{position >= back ? position - back : 0, reason};
    return false;
  }
};

}  // namespace

std::string textPlace(const std::string& text, size_t offset) {
  offset = std::min(offset, text.size());
  const size_t lines = size_t(std::count(text.begin(), text.begin() + std::ptrdiff_t(offset), '\n'));
  const size_t newline = offset == 0 ? std::string::npos : text.rfind('\n', offset - 1);
  const size_t column = offset - (newline == std::string::npos ? 0 : newline + 1) + 1;
  return "line " + std::to_string(lines + 1) + ", column " + std::to_string(column);
}

std::optional<JsonSyntaxError> findJsonSyntaxError(const std::string& text) {
  SyntaxCheck check;
  nlohmann::json::sax_parse(text, &check);
  return check.error;
}

size_t jsonValueOffset(const std::string& text, const JsonPath& path) {
  size_t found = 0, depth = 0;
  bool rooted = false;  // the document's value seen (bytes after it are not its parts)
  walkJson(text, std::string::npos, [&](const JsonPath& at, size_t offset) {
    const bool onTheWay = at.size() <= path.size() && std::equal(at.begin(), at.end(), path.begin());
    if (onTheWay && (at.empty() ? !rooted : at.size() > depth)) {
      found = offset;
      depth = at.size();
      rooted = true;
    }
    return !(onTheWay && at.size() == path.size());
  });
  return found;
}

JsonPath jsonPathAt(const std::string& text, size_t offset) {
  return walkJson(text, offset, [](const JsonPath&, size_t) { return true; });
}

}  // namespace afterglow
