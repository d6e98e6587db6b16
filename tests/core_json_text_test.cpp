// Places in a JSON file's text (core/json_text.h): line and column of a byte, the syntax errors
// nlohmann::json refuses (a NaN, a 1e999, a trailing comma) with the byte that broke them,
// which entry a place is in, and where a value starts.
#include <string>

#include <gtest/gtest.h>

#include "afterglow/core/json_text.h"

namespace afterglow::test {
namespace {

TEST(JsonText, PlacesCountLinesAndColumnsFromOne) {
  const std::string text = "{\n  \"a\": 1,\n  \"b\": [2, 3]\n}\n";
  EXPECT_EQ(textPlace(text, 0), "line 1, column 1");
  EXPECT_EQ(textPlace(text, 1), "line 1, column 2");  // the newline ends line 1
  EXPECT_EQ(textPlace(text, 2), "line 2, column 1");
  EXPECT_EQ(textPlace(text, text.find("[2")), "line 3, column 8");
  EXPECT_EQ(textPlace(text, 1000), "line 5, column 1");  // clamped to the end
}

TEST(JsonText, SyntaxErrorsSayWhyAndWhere) {
  EXPECT_FALSE(findJsonSyntaxError("{\"a\": [1, 2.5e3, -1]}"));
  const std::string nan = "{\"p\": [[0, 0],\n  [0, NaN]]}";
  std::optional<JsonSyntaxError> e = findJsonSyntaxError(nan);
  ASSERT_TRUE(e);
  EXPECT_EQ(e->offset, nan.find('N'));
  EXPECT_NE(e->reason.find("invalid literal"), std::string::npos) << e->reason;
  EXPECT_EQ(e->reason.find("[json.exception"), std::string::npos) << e->reason;
  EXPECT_EQ(e->reason.find("line"), std::string::npos) << "the caller places it: " << e->reason;
  EXPECT_EQ(jsonPathAt(nan, e->offset), (JsonPath{"p", "1", "1"}));

  // Beyond a double: nlohmann refuses it whole (out_of_range 406); the place is its first byte.
  const std::string huge = "{\"p\": [[0, 0],\n  [0, -1e999]]}";
  e = findJsonSyntaxError(huge);
  ASSERT_TRUE(e);
  EXPECT_EQ(e->offset, huge.find("-1e999"));
  EXPECT_NE(e->reason.find("1e999"), std::string::npos) << e->reason;
  EXPECT_EQ(jsonPathAt(huge, e->offset), (JsonPath{"p", "1", "1"}));

  // A trailing comma breaks the entry it promised.
  const std::string comma = "{\"p\": [[0, 0], [1, 1], ]}";
  e = findJsonSyntaxError(comma);
  ASSERT_TRUE(e);
  EXPECT_EQ(e->offset, comma.rfind(']'));
  EXPECT_EQ(jsonPathAt(comma, e->offset), (JsonPath{"p", "2"}));
  EXPECT_TRUE(findJsonSyntaxError(""));
}

TEST(JsonText, ValuesAreFoundByTheirPath) {
  const std::string text =
      "{\"positions\": [[0, 0, 0],\n [1, \"x\", 0]], \"names\": {\"3\": \"door\"},\n"
      " \"s\": \"a,]}\\\"b\", \"after\": {\"k\": [true, null]}}";
  EXPECT_EQ(jsonValueOffset(text, {"positions", "1"}), text.find("[1,"));
  EXPECT_EQ(jsonValueOffset(text, {"positions", "1", "1"}), text.find("\"x\""));
  EXPECT_EQ(jsonValueOffset(text, {"names", "3"}), text.find("\"door\""));
  // Strings with brackets, commas and escaped quotes are stepped over whole.
  EXPECT_EQ(jsonValueOffset(text, {"after", "k", "1"}), text.find("null"));
  // A missing part: where the deepest part that is there starts.
  EXPECT_EQ(jsonValueOffset(text, {"positions", "7"}), text.find("[[0"));
  EXPECT_EQ(jsonValueOffset(text, {"nowhere"}), 0u);
}

// Bytes JSON has no place for, a NUL among them (strchr finds NUL in every delimiter list),
// are stepped over one at a time: the walk ends. The fuzzer's input hung it.
TEST(JsonText, StrayBytesAndNulsAreSteppedOver) {
  const std::string text("{\"positios\": [], \"tetrahedra\": []}\0\0\0\"\n\x01@", 41);
  EXPECT_EQ(jsonValueOffset(text, {"positions"}), 0u);
  EXPECT_EQ(jsonValueOffset(text, {"tetrahedra"}), text.find("[]}"));
  EXPECT_EQ(jsonPathAt(text, text.size()), JsonPath{});
  const std::string inside("[1, \0\0, 2]", 10);
  EXPECT_EQ(jsonValueOffset(inside, {"2"}), inside.find('2'));
}

}  // namespace
}  // namespace afterglow::test
