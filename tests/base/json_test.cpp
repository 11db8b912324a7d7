#include "common/base/json.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "common/base/errors.h"

namespace meshmend {
namespace {

TEST(Json, RendersValuesInOrder) {
  JsonObject inner;
  inner.set("a", 1).set("b", "x\"y");
  JsonObject j;
  j.set("int", 42)
      .set("neg", -7L)
      .set("real", 0.5)
      .set("nan", std::nan(""))
      .set("flag", false)
      .set("none", std::optional<double>())
      .set("obj", inner)
      .set("list", std::vector<double>{1, 2.5})
      .set("names", std::vector<std::string>{"p", "q"});
  EXPECT_EQ(j.str(),
            "{\"int\": 42, \"neg\": -7, \"real\": 0.5, \"nan\": null, \"flag\": false, "
            "\"none\": null, \"obj\": {\"a\": 1, \"b\": \"x\\\"y\"}, \"list\": [1, 2.5], "
            "\"names\": [\"p\", \"q\"]}");
}

TEST(Json, SettingAKeyAgainReplacesIt) {
  JsonObject j;
  j.set("k", 1).set("k", 2);
  EXPECT_EQ(j.str(), "{\"k\": 2}");
}

TEST(Json, EscapesControlCharacters) {
  EXPECT_EQ(jsonQuote("a\nb\t\x01"), "\"a\\nb\\t\\u0001\"");
}

TEST(Json, WritesFileOneKeyPerLine) {
  const std::string path = ::testing::TempDir() + "/meshmend_json_test.json";
  JsonObject j;
  j.set("faces", 12).set("is_closed", true);
  writeJsonFile(path, j);
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  EXPECT_EQ(s.str(), "{\n  \"faces\": 12,\n  \"is_closed\": true\n}\n");
  std::remove(path.c_str());
}

TEST(Json, UnwritablePathThrowsWithThePath) {
  try {
    writeJsonFile("/nonexistent-folder/report.json", JsonObject());
    FAIL();
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-folder/report.json"), std::string::npos);
  }
}

}  // namespace
}  // namespace meshmend
