#include "plugins/bridge/filter_support.h"

#include <cstdint>
#include <fstream>
#include <sstream>

#include <QFileInfo>

namespace meshmend::bridge {

void writeReport(const QString& path, const JsonObject& report) {
  if (!path.trimmed().isEmpty()) writeJsonFile(toStd(path.trimmed()), report);
}

namespace {

struct FileCounts {
  long vertices = -1, faces = -1, strips = -1;
};

FileCounts offCounts(std::istream& in) {
  FileCounts c;
  std::string line;
  bool sawKeyword = false;
  while (std::getline(in, line)) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    std::istringstream words(line);
    std::string first;
    if (!(words >> first)) continue;
    if (!sawKeyword && first.size() >= 3 && first.compare(first.size() - 3, 3, "OFF") == 0) {
      sawKeyword = true;
      long v, f;
      if (words >> v >> f) return {v, f, -1};  // counts on the keyword line
      continue;
    }
    std::istringstream counts(line);
    long v, f;
    if (counts >> v >> f) return {v, f, -1};
    return c;
  }
  return c;
}

FileCounts plyCounts(std::istream& in) {
  FileCounts c;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string keyword, element;
    long n = -1;
    words >> keyword;
    if (keyword == "end_header") break;
    if (keyword != "element" || !(words >> element >> n)) continue;
    if (element == "vertex") c.vertices = n;
    if (element == "face") c.faces = n;
    if (element == "tristrips") c.strips = n;
  }
  return c;
}

FileCounts objCounts(std::istream& in) {
  FileCounts c{0, 0, -1};
  std::string line;
  while (std::getline(in, line)) {
    if (line.size() > 1 && line[0] == 'v' && (line[1] == ' ' || line[1] == '\t')) ++c.vertices;
    if (line.size() > 1 && line[0] == 'f' && (line[1] == ' ' || line[1] == '\t')) ++c.faces;
  }
  return c;
}

FileCounts stlCounts(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  FileCounts c;
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(80);
  std::uint32_t n = 0;
  if (size >= 84 && in.read(reinterpret_cast<char*>(&n), 4) &&
      std::streamoff(84) + std::streamoff(50) * n == size) {
    c.faces = long(n);
  } else {  // ASCII: count facets
    in.clear();
    in.seekg(0);
    std::string word;
    c.faces = 0;
    while (in >> word) c.faces += word == "endfacet";
  }
  c.vertices = 3 * c.faces;
  return c;
}

}  // namespace

ImportNotes importNotes(const MeshModel& model) {
  ImportNotes r;
  const QFileInfo info(model.fullName());
  if (!info.isFile()) return r;
  const std::string path = toStd(info.absoluteFilePath());
  const QString ext = info.suffix().toLower();
  FileCounts c;
  std::ifstream in(path, std::ios::binary);
  if (ext == "off")
    c = offCounts(in);
  else if (ext == "ply")
    c = plyCounts(in);
  else if (ext == "obj")
    c = objCounts(in);
  else if (ext == "stl")
    c = stlCounts(path);
  else
    return r;
  r.file_vertices = c.vertices;
  r.file_faces = c.faces;
  const long vn = model.cm.vn, fn = model.cm.fn;
  if (ext == "stl" && c.vertices >= 0 && vn != c.vertices)
    r.notes.push_back("MeshLab unified the STL's duplicated vertices: the file stores " +
                      std::to_string(c.vertices) + " vertex records (3 per facet), the layer has " +
                      std::to_string(vn));
  else if (c.vertices >= 0 && vn != c.vertices)
    r.notes.push_back("MeshLab's importer dropped " + std::to_string(c.vertices - vn) +
                      " of the file's " + std::to_string(c.vertices) +
                      " vertices (non-finite coordinates)");
  if (c.strips > 0)
    r.notes.push_back("the file stores triangle strips; MeshLab converted them to " +
                      std::to_string(fn) + " triangles");
  else if (c.faces >= 0 && fn > c.faces)
    r.notes.push_back("MeshLab triangulated the file's polygons: " + std::to_string(c.faces) +
                      " faces became " + std::to_string(fn) + " triangles");
  else if (c.faces >= 0 && fn < c.faces)
    r.notes.push_back("MeshLab's importer dropped " + std::to_string(c.faces - fn) +
                      " of the file's " + std::to_string(c.faces) +
                      " faces (faces with a repeated vertex, or referring to dropped vertices)");
  return r;
}

}  // namespace meshmend::bridge
