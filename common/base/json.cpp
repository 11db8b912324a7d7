#include "common/base/json.h"

#include <cmath>
#include <cstdio>
#include <fstream>

#include "common/base/errors.h"

namespace meshmend {

std::string jsonQuote(const std::string& text) {
  std::string out = "\"";
  for (unsigned char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += char(c);
        }
    }
  }
  return out + "\"";
}

std::string jsonNumber(double value) {
  if (!std::isfinite(value)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", value);
  return buf;
}

JsonObject& JsonObject::setRaw(const std::string& key, std::string rendered) {
  for (auto& member : members_)
    if (member.first == key) {
      member.second = std::move(rendered);
      return *this;
    }
  members_.emplace_back(key, std::move(rendered));
  return *this;
}

JsonObject& JsonObject::set(const std::string& key, bool value) {
  return setRaw(key, value ? "true" : "false");
}
JsonObject& JsonObject::set(const std::string& key, std::int64_t value) {
  return setRaw(key, std::to_string(value));
}
JsonObject& JsonObject::set(const std::string& key, double value) {
  return setRaw(key, jsonNumber(value));
}
JsonObject& JsonObject::set(const std::string& key, const std::optional<double>& value) {
  return value ? set(key, *value) : setNull(key);
}
JsonObject& JsonObject::set(const std::string& key, const std::string& value) {
  return setRaw(key, jsonQuote(value));
}
JsonObject& JsonObject::set(const std::string& key, const JsonObject& value) {
  return setRaw(key, value.str(false));
}
JsonObject& JsonObject::set(const std::string& key, const std::vector<double>& values) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i) out += (i ? ", " : "") + jsonNumber(values[i]);
  return setRaw(key, out + "]");
}
JsonObject& JsonObject::set(const std::string& key, const std::vector<std::string>& values) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i) out += (i ? ", " : "") + jsonQuote(values[i]);
  return setRaw(key, out + "]");
}
JsonObject& JsonObject::set(const std::string& key, const std::vector<JsonObject>& values) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i) out += (i ? ", " : "") + values[i].str(false);
  return setRaw(key, out + "]");
}
JsonObject& JsonObject::setNull(const std::string& key) {
  return setRaw(key, "null");
}

std::string JsonObject::str(bool multiline) const {
  if (members_.empty()) return "{}";
  std::string out = multiline ? "{\n" : "{";
  for (std::size_t i = 0; i < members_.size(); ++i) {
    if (multiline) out += "  ";
    out += jsonQuote(members_[i].first) + ": " + members_[i].second;
    if (i + 1 < members_.size()) out += multiline ? ",\n" : ", ";
  }
  return out + (multiline ? "\n}" : "}");
}

void writeJsonFile(const std::string& path, const JsonObject& object) {
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file)
    throw InvalidInputError("cannot write the report file '" + path +
                            "': check that its folder exists and is writable");
  file << object.str(true) << '\n';
  if (!file.flush())
    throw InvalidInputError("writing the report file '" + path + "' failed (disk full?)");
}

}  // namespace meshmend
