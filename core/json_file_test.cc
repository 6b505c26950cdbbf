#include "core/json_file.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;

TEST(JsonFileTest, SyntaxErrorNamesFileLineAndColumn) {
  testing::TempDir dir;
  testing::WriteFile(dir / "m.json", "{\n  \"a\": 1,\n  \"b\": ]\n}\n");
  try {
    ReadJsonFile(dir / "m.json");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("m.json: invalid JSON at line 3, column 8"));
  }
}

// Syntactically valid, but the number does not fit a double: an Error naming the file, not
// nlohmann's own exception (found by the manifest fuzzer).
TEST(JsonFileTest, NumberBeyondDoubleRangeIsAnErrorNamingTheFile) {
  testing::TempDir dir;
  testing::WriteFile(dir / "m.json", "{\"light\": 1e99999}\n");
  try {
    ReadJsonFile(dir / "m.json");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("m.json: unreadable JSON"));
  }
}

TEST(JsonFileTest, ReaderNamesTheJsonPathOfAFault) {
  const auto doc = nlohmann::json::parse(R"({"images": [{"light": [1, 2]}, {"light": "up"}]})");
  JsonReader reader(doc, "m.json");
  EXPECT_EQ(reader["images"][0]["light"].Numbers().size(), 2u);
  try {
    reader["images"][1]["light"].Numbers();
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "m.json: images[1].light: expected an array of numbers");
  }
  EXPECT_THROW(reader["missing"], Error);
  EXPECT_THROW(reader["images"][5], Error);
}

TEST(JsonFileTest, WriteThenReadRoundTrips) {
  testing::TempDir dir;
  const nlohmann::json value = {{"x", 1.5}, {"list", {1, 2, 3}}};
  WriteJsonFile(dir / "v.json", value);
  EXPECT_EQ(ReadJsonFile(dir / "v.json"), value);
}

}  // namespace
}  // namespace photomat
