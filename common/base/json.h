// A small ordered JSON object writer for the filters' machine-readable reports
// (the filters' `report_file`). Values are rendered when set; keys keep their order.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace meshmend {

class JsonObject {
 public:
  JsonObject& set(const std::string& key, bool value);
  JsonObject& set(const std::string& key, int value) { return set(key, std::int64_t(value)); }
  JsonObject& set(const std::string& key, long long value) { return set(key, std::int64_t(value)); }
  JsonObject& set(const std::string& key, unsigned long value) {
    return set(key, std::int64_t(value));
  }
  JsonObject& set(const std::string& key, unsigned long long value) {
    return set(key, std::int64_t(value));
  }
  JsonObject& set(const std::string& key, unsigned value) { return set(key, std::int64_t(value)); }
  JsonObject& set(const std::string& key, std::int64_t value);
  JsonObject& set(const std::string& key, double value);  // non-finite -> null
  JsonObject& set(const std::string& key, const std::optional<double>& value);
  JsonObject& set(const std::string& key, const std::string& value);
  JsonObject& set(const std::string& key, const char* value) {
    return set(key, std::string(value));
  }
  JsonObject& set(const std::string& key, const JsonObject& value);
  JsonObject& set(const std::string& key, const std::vector<double>& values);
  JsonObject& set(const std::string& key, const std::vector<std::string>& values);
  JsonObject& set(const std::string& key, const std::vector<JsonObject>& values);
  JsonObject& setNull(const std::string& key);

  bool empty() const { return members_.empty(); }
  // One line per top-level key when `multiline`, nested values on one line.
  std::string str(bool multiline = false) const;

 private:
  JsonObject& setRaw(const std::string& key, std::string rendered);
  std::vector<std::pair<std::string, std::string>> members_;
};

// JSON string literal (quoted, escaped).
std::string jsonQuote(const std::string& text);
// A finite double in 10 significant digits, as meshcheck prints it ("null" otherwise).
std::string jsonNumber(double value);

// Writes `object` to `path` (one line per key). Throws InvalidInputError with
// the path in the message when the file cannot be written.
void writeJsonFile(const std::string& path, const JsonObject& object);

}  // namespace meshmend
