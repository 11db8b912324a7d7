#include "plugins/bridge/filter_plugin.h"

#include <cctype>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "plugins/bridge/filter_support.h"

namespace meshmend::bridge {

void FilterAdapter::addFilters(QObject* plugin, std::initializer_list<FilterIDType> filters) {
  for (FilterIDType id : filters) {
    typeList.push_back(id);
    actionList.push_back(new QAction(filterName(id), plugin));
  }
}

void FilterAdapter::publishReport(const RichParameterList& parameters, const JsonObject& report) {
  writeReport(parameters.getString("report_file"), report);
  published_ = report;
}

#if MESHMEND_MESHLAB_API == 2022

RichParameterList FilterAdapter::initParameterList(const QAction* a, const MeshDocument& md) {
  RichParameterList parameters;
  // The layer parameters keep a pointer to the document they choose from.
  initParameters(mutableAction(a), const_cast<MeshDocument&>(md), parameters);
  return parameters;
}

std::map<std::string, QVariant> FilterAdapter::applyFilter(const QAction* a,
                                                           const RichParameterList& parameters,
                                                           MeshDocument& md, unsigned int&,
                                                           vcg::CallBackPos* cb) {
  published_ = JsonObject();
  QString error;
  const bool ok = guarded(
      error, [&] { apply(mutableAction(a), md, parameters, cb); },
      [this](const std::string& message) { log(message); });
  if (!ok) throw MLException(error);
  return resultMap(published_);
}

namespace {

// The values of a JSON text as JsonObject renders them (no insignificant
// whitespace inside values): each value is located, classified and converted.
class JsonScanner {
 public:
  explicit JsonScanner(std::string_view text) : text_(text) {}

  void skipSpace() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  }
  bool consume(char c) {
    skipSpace();
    if (pos_ < text_.size() && text_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  char peek() {
    skipSpace();
    return pos_ < text_.size() ? text_[pos_] : '\0';
  }
  void expect(char c) {
    if (!consume(c)) fail(std::string("expected '") + c + "'");
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw std::logic_error("report JSON: " + what + " at offset " + std::to_string(pos_));
  }

  std::string string() {
    expect('"');
    std::string out;
    while (pos_ < text_.size() && text_[pos_] != '"') {
      char c = text_[pos_++];
      if (c != '\\') {
        out += c;
        continue;
      }
      if (pos_ >= text_.size()) fail("unterminated escape");
      const char e = text_[pos_++];
      switch (e) {
        case 'n':
          out += '\n';
          break;
        case 't':
          out += '\t';
          break;
        case 'r':
          out += '\r';
          break;
        case 'b':
          out += '\b';
          break;
        case 'f':
          out += '\f';
          break;
        case 'u': {
          if (pos_ + 4 > text_.size()) fail("short \\u escape");
          const unsigned code =
              unsigned(std::stoul(std::string(text_.substr(pos_, 4)), nullptr, 16));
          pos_ += 4;
          appendUtf8(out, code);
          break;
        }
        default:
          out += e;  // \" \\ \/
      }
    }
    if (pos_ >= text_.size()) fail("unterminated string");
    ++pos_;
    return out;
  }

  // Skips one value; returns its text.
  std::string_view value() {
    skipSpace();
    const std::size_t start = pos_;
    const char c = peek();
    if (c == '"') {
      string();
    } else if (c == '{' || c == '[') {
      const char close = c == '{' ? '}' : ']';
      ++pos_;
      if (!consume(close)) {
        do {
          if (c == '{') {
            string();
            expect(':');
          }
          value();
        } while (consume(','));
        expect(close);
      }
    } else {
      while (pos_ < text_.size() &&
             std::string_view(",]} \n").find(text_[pos_]) == std::string_view::npos)
        ++pos_;
      if (pos_ == start) fail("expected a value");
    }
    return text_.substr(start, pos_ - start);
  }

 private:
  static void appendUtf8(std::string& out, unsigned code) {
    if (code < 0x80) {
      out += char(code);
    } else if (code < 0x800) {
      out += char(0xC0 | (code >> 6));
      out += char(0x80 | (code & 0x3F));
    } else {
      out += char(0xE0 | (code >> 12));
      out += char(0x80 | ((code >> 6) & 0x3F));
      out += char(0x80 | (code & 0x3F));
    }
  }

  std::string_view text_;
  std::size_t pos_ = 0;
};

bool isNumberText(std::string_view t) {
  return !t.empty() && (t[0] == '-' || std::isdigit(static_cast<unsigned char>(t[0])));
}

QVariant numberVariant(std::string_view t) {
  const std::string s(t);
  if (s.find_first_of(".eE") == std::string::npos) {
    const long long v = std::stoll(s);
    if (v >= std::numeric_limits<int>::min() && v <= std::numeric_limits<int>::max())
      return QVariant(int(v));
    return QVariant(double(v));
  }
  return QVariant(std::stod(s));
}

// An array whose elements are all numbers (or null) as a vector; nullopt otherwise.
std::optional<Eigen::VectorXd> numberArray(std::string_view t) {
  JsonScanner scan(t);
  scan.expect('[');
  std::vector<double> values;
  if (!scan.consume(']')) {
    do {
      const std::string_view element = scan.value();
      if (element == "null")
        values.push_back(std::numeric_limits<double>::quiet_NaN());
      else if (isNumberText(element))
        values.push_back(std::stod(std::string(element)));
      else
        return std::nullopt;
    } while (scan.consume(','));
    scan.expect(']');
  }
  Eigen::VectorXd v(Eigen::Index(values.size()));
  for (std::size_t i = 0; i < values.size(); ++i) v[Eigen::Index(i)] = values[i];
  return v;
}

}  // namespace

std::map<std::string, QVariant> resultMap(const JsonObject& report) {
  std::map<std::string, QVariant> result;
  const std::string text = report.str();
  JsonScanner scan(text);
  scan.expect('{');
  if (scan.consume('}')) return result;
  do {
    const std::string key = scan.string();
    scan.expect(':');
    const std::string_view value = scan.value();
    if (value == "true" || value == "false") {
      result[key] = QVariant(value == "true");
    } else if (value == "null") {
      result[key] = QVariant(std::numeric_limits<double>::quiet_NaN());
    } else if (isNumberText(value)) {
      result[key] = numberVariant(value);
    } else if (value.front() == '[') {
      if (auto numbers = numberArray(value)) result[key] = QVariant::fromValue(*numbers);
    }
  } while (scan.consume(','));
  scan.expect('}');
  return result;
}

#else

bool FilterAdapter::applyFilter(QAction* a, MeshDocument& md, const RichParameterList& parameters,
                                vcg::CallBackPos* cb) {
  published_ = JsonObject();
  return guarded(
      errorMessage, [&] { apply(a, md, parameters, cb); },
      [this](const std::string& message) { Log(message); });
}

#endif

}  // namespace meshmend::bridge
