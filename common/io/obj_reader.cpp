#include "common/io/obj_reader.h"

#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/base/errors.h"

namespace meshmend {

namespace {

class ObjParser {
 public:
  explicit ObjParser(std::string path) : path_(std::move(path)) {}

  ObjData run() {
    std::ifstream in(path_, std::ios::binary);
    if (!in) throw InvalidInputError("cannot open '" + path_ + "': check the path");
    std::string line, logical;
    while (std::getline(in, line)) {
      ++lineNumber_;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (!line.empty() && line.back() == '\\') {  // continuation
        logical += line.substr(0, line.size() - 1) + ' ';
        continue;
      }
      logical += line;
      parseLine(logical);
      logical.clear();
    }
    if (!logical.empty()) parseLine(logical);
    if (data_.positions.empty())
      throw InvalidInputError("'" + path_ + "' defines no vertex ('v' line): not a mesh");
    checkIndices();
    if (skippedLines_ > 0)
      data_.warnings.push_back(std::to_string(skippedLines_) +
                               " lines with unsupported statements were skipped (" + firstSkipped_ +
                               ")");
    return std::move(data_);
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw InvalidInputError("'" + path_ + "', line " + std::to_string(lineNumber_) + ": " + what);
  }

  double number(std::istringstream& words, const char* what) {
    std::string token;
    if (!(words >> token)) fail(std::string("missing ") + what);
    errno = 0;
    char* end = nullptr;
    const double v = std::strtod(token.c_str(), &end);
    if (end == token.c_str() || *end != '\0') fail("'" + token + "' is not a number");
    if (!std::isfinite(v)) fail(std::string("non-finite ") + what + " '" + token + "'");
    return v;
  }

  // Resolves a 1-based (or negative, relative) OBJ index against `count`
  // elements defined so far; out-of-range indices are checked at the end.
  int resolve(const std::string& token, std::size_t count) {
    char* end = nullptr;
    const long i = std::strtol(token.c_str(), &end, 10);
    if (end == token.c_str() || *end != '\0') fail("bad index '" + token + "'");
    if (i == 0) fail("index 0 (OBJ indices start at 1)");
    // Beyond int, an index would wrap (and -1 means "none"): no file has
    // that many elements.
    if (i > INT_MAX || i < -long(INT_MAX)) fail("index '" + token + "' is out of range");
    return i > 0 ? int(i - 1) : int(long(count) + i);
  }

  void parseLine(const std::string& line) {
    std::istringstream words(line);
    std::string keyword;
    if (!(words >> keyword) || keyword[0] == '#') return;
    if (keyword == "v") {
      const double x = number(words, "x"), y = number(words, "y"), z = number(words, "z");
      data_.positions.emplace_back(x, y, z);
      std::vector<double> rest;
      std::string token;
      while (words >> token) rest.push_back(std::strtod(token.c_str(), nullptr));
      if (rest.size() >= 3) {  // "v x y z r g b" colour extension
        data_.vertex_colors.resize(data_.positions.size() - 1, {1, 1, 1});
        data_.vertex_colors.push_back({float(rest[0]), float(rest[1]), float(rest[2])});
      } else if (!data_.vertex_colors.empty()) {
        data_.vertex_colors.push_back({1, 1, 1});
      }
    } else if (keyword == "vt") {
      const double u = number(words, "u");
      std::string token;
      const double v = (words >> token) ? std::strtod(token.c_str(), nullptr) : 0.0;
      data_.texcoords.push_back({u, v});
    } else if (keyword == "vn") {
      const double x = number(words, "x"), y = number(words, "y"), z = number(words, "z");
      data_.normals.emplace_back(x, y, z);
    } else if (keyword == "f" || keyword == "fo") {
      std::vector<ObjCorner> polygon;
      std::string token;
      while (words >> token) {
        ObjCorner c;
        const std::size_t s1 = token.find('/');
        c.vertex = resolve(token.substr(0, s1), data_.positions.size());
        if (s1 != std::string::npos) {
          const std::size_t s2 = token.find('/', s1 + 1);
          const std::string t = token.substr(s1 + 1, s2 == std::string::npos ? s2 : s2 - s1 - 1);
          if (!t.empty()) c.texcoord = resolve(t, data_.texcoords.size());
          if (s2 != std::string::npos && s2 + 1 < token.size())
            c.normal = resolve(token.substr(s2 + 1), data_.normals.size());
        }
        polygon.push_back(c);
      }
      if (polygon.size() < 3) {
        ++faceWithFewCorners_;
        return;
      }
      data_.polygons.push_back(std::move(polygon));
      data_.polygon_material.push_back(currentMaterial_);
    } else if (keyword == "usemtl") {
      std::string name;
      words >> name;
      currentMaterial_ = -1;
      for (std::size_t i = 0; i < data_.materials.size(); ++i)
        if (data_.materials[i].name == name) currentMaterial_ = int(i);
      if (currentMaterial_ < 0) {  // used before (or without) its definition
        data_.materials.push_back(ObjMaterial{name, {0.8f, 0.8f, 0.8f}, 1, {}});
        currentMaterial_ = int(data_.materials.size()) - 1;
      }
    } else if (keyword == "mtllib") {
      std::string name;
      std::getline(words >> std::ws, name);
      readMaterials(name);
    } else if (keyword == "o" || keyword == "g" || keyword == "s" || keyword == "vp") {
      // grouping and smoothing statements carry no geometry we keep
    } else {
      if (skippedLines_++ == 0)
        firstSkipped_ = "'" + keyword + "' at line " + std::to_string(lineNumber_);
    }
  }

  void readMaterials(const std::string& name) {
    const std::size_t slash = path_.find_last_of('/');
    const std::string folder = slash == std::string::npos ? "" : path_.substr(0, slash + 1);
    // Only a regular file: a name that leads to a device or a pipe
    // (/dev/zero has no line end) would never finish.
    std::error_code error;
    const bool regular = std::filesystem::is_regular_file(folder + name, error);
    std::ifstream in;
    if (regular) in.open(folder + name);
    if (!regular || !in) {
      data_.warnings.push_back("material library '" + name + "' not found; colours ignored");
      return;
    }
    std::string line;
    ObjMaterial* current = nullptr;
    while (std::getline(in, line)) {
      if (!line.empty() && line.back() == '\r') line.pop_back();
      std::istringstream words(line);
      std::string keyword;
      if (!(words >> keyword)) continue;
      if (keyword == "newmtl") {
        std::string material;
        words >> material;
        int found = -1;
        for (std::size_t i = 0; i < data_.materials.size(); ++i)
          if (data_.materials[i].name == material) found = int(i);
        if (found < 0) {
          data_.materials.push_back(ObjMaterial{material, {0.8f, 0.8f, 0.8f}, 1, {}});
          found = int(data_.materials.size()) - 1;
        }
        current = &data_.materials[found];
      } else if (current && keyword == "Kd") {
        words >> current->diffuse[0] >> current->diffuse[1] >> current->diffuse[2];
      } else if (current && keyword == "d") {
        words >> current->opacity;
      } else if (current && keyword == "Tr") {
        float tr = 0;
        words >> tr;
        current->opacity = 1 - tr;
      } else if (current && keyword == "map_Kd") {
        std::string file;
        std::getline(words >> std::ws, file);
        current->diffuse_texture = file.substr(file.find_last_of(' ') + 1);  // options first
      }
    }
  }

  void checkIndices() {
    auto check = [&](std::size_t polygon, int index, std::size_t count, const char* what) {
      if (index < 0 || std::size_t(index) >= count)
        throw InvalidInputError("'" + path_ + "': face " + std::to_string(polygon) + " refers to " +
                                what + " " + std::to_string(long(index) + 1) +
                                ", but the file has " + std::to_string(count));
    };
    for (std::size_t p = 0; p < data_.polygons.size(); ++p)
      for (const ObjCorner& c : data_.polygons[p]) {
        check(p, c.vertex, data_.positions.size(), "vertex");
        if (c.texcoord != -1) check(p, c.texcoord, data_.texcoords.size(), "texture coordinate");
        if (c.normal != -1) check(p, c.normal, data_.normals.size(), "normal");
      }
    if (faceWithFewCorners_ > 0)
      data_.warnings.push_back(std::to_string(faceWithFewCorners_) +
                               " faces with fewer than 3 corners were skipped");
  }

  std::string path_;
  ObjData data_;
  std::size_t lineNumber_ = 0;
  int currentMaterial_ = -1;
  std::size_t skippedLines_ = 0, faceWithFewCorners_ = 0;
  std::string firstSkipped_;
};

}  // namespace

ObjData readObj(const std::string& path) {
  return ObjParser(path).run();
}

}  // namespace meshmend
