// plugin_apply PLUGIN.so FILTER OUT_FOLDER IN.off... [-- NAME=VALUE...]:
// a MeshLab 2020.09 host in one process, for checking what a filter leaves
// in the document whether it succeeds or fails (meshlabserver saves nothing
// after a failed filter). Loads the plugin the way MeshLab does
// (QPluginLoader + qobject_cast), each OFF file into its own layer (float
// coordinates, as MeshLab stores them), applies FILTER with its default
// parameters and the given overrides (bool, int, float or string values,
// by the parameter's type), then writes every layer of the document, as it
// is after the filter, to OUT_FOLDER/<index>.off (coordinates printed with
// nine significant digits: floats read back exactly) and prints one JSON
// object: ok, the error message, the log, and each layer's label and file.
#include <common/GLLogStream.h>
#include <common/interfaces.h>
#include <common/meshmodel.h>
#include <QApplication>
#include <QFileInfo>
#include <QPluginLoader>

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "common/base/json.h"

namespace {

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "plugin_apply: %s\n", what.c_str());
  std::exit(2);
}

// A plain OFF file (triangles) into a new layer.
void readOff(MeshDocument& document, const std::string& path) {
  std::ifstream in(path);
  std::string magic;
  std::size_t nv = 0, nf = 0, ne = 0;
  if (!(in >> magic >> nv >> nf >> ne) || magic != "OFF") fail(path + ": not an OFF file");
  MeshModel* m = document.addNewMesh("", QFileInfo(QString::fromStdString(path)).baseName());
  auto vi = vcg::tri::Allocator<CMeshO>::AddVertices(m->cm, nv);
  for (std::size_t v = 0; v < nv; ++v, ++vi) {
    double x, y, z;
    if (!(in >> x >> y >> z)) fail(path + ": short vertex list");
    vi->P() = Point3m(Scalarm(x), Scalarm(y), Scalarm(z));
  }
  auto fi = vcg::tri::Allocator<CMeshO>::AddFaces(m->cm, nf);
  for (std::size_t f = 0; f < nf; ++f, ++fi) {
    std::size_t k, a, b, c;
    if (!(in >> k >> a >> b >> c) || k != 3 || a >= nv || b >= nv || c >= nv)
      fail(path + ": faces must be triangles on listed vertices");
    fi->V(0) = &m->cm.vert[a];
    fi->V(1) = &m->cm.vert[b];
    fi->V(2) = &m->cm.vert[c];
  }
}

// The layer's live vertices and faces (deleted ones left out, indices compacted).
void writeOff(const CMeshO& cm, const std::string& path) {
  std::vector<int> index(cm.vert.size(), -1);
  int n = 0;
  for (std::size_t v = 0; v < cm.vert.size(); ++v)
    if (!cm.vert[v].IsD()) index[v] = n++;
  std::FILE* out = std::fopen(path.c_str(), "w");
  if (!out) fail("cannot write " + path);
  std::fprintf(out, "OFF\n%d %d 0\n", n, cm.fn);
  for (const auto& v : cm.vert)
    if (!v.IsD())
      std::fprintf(out, "%.9g %.9g %.9g\n", double(v.cP()[0]), double(v.cP()[1]),
                   double(v.cP()[2]));
  for (const auto& f : cm.face)
    if (!f.IsD())
      std::fprintf(out, "3 %d %d %d\n", index[f.cV(0) - &cm.vert[0]], index[f.cV(1) - &cm.vert[0]],
                   index[f.cV(2) - &cm.vert[0]]);
  std::fclose(out);
}

// NAME=VALUE into the parameter of that name, by its type (a layer
// parameter takes the layer's index in loading order).
void setParameter(MeshDocument& document, RichParameterList& parameters,
                  const std::string& assignment) {
  const std::size_t eq = assignment.find('=');
  if (eq == std::string::npos) fail("expected NAME=VALUE, got " + assignment);
  const QString name = QString::fromStdString(assignment.substr(0, eq));
  const QString value = QString::fromStdString(assignment.substr(eq + 1));
  if (parameters.findParameter(name) == parameters.end())
    fail("no parameter " + name.toStdString());
  const Value& current = parameters.getParameterByName(name).value();
  if (current.isMesh()) {
    const int index = value.toInt();
    if (index < 0 || index >= document.meshList.size()) fail("no layer " + value.toStdString());
    parameters.setValue(name, MeshValue(document.meshList[index]));
  } else if (current.isBool())
    parameters.setValue(name, BoolValue(value == "true" || value == "1"));
  else if (current.isEnum())
    parameters.setValue(name, EnumValue(value.toInt()));
  else if (current.isInt())
    parameters.setValue(name, IntValue(value.toInt()));
  else if (current.isAbsPerc())
    parameters.setValue(name, AbsPercValue(value.toFloat()));
  else if (current.isFloat())
    parameters.setValue(name, FloatValue(value.toFloat()));
  else if (current.isString())
    parameters.setValue(name, StringValue(value));
  else
    fail("parameter " + name.toStdString() + ": only bool, int, float and string can be set");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5)
    fail("usage: plugin_apply PLUGIN.so FILTER OUT_FOLDER IN.off... [-- NAME=VALUE...]");
  qputenv("QT_QPA_PLATFORM", "offscreen");
  QApplication app(argc, argv);
  const std::string filterName = argv[2], outFolder = argv[3];
  MeshDocument document;
  int i = 4;
  for (; i < argc && std::string(argv[i]) != "--"; ++i) readOff(document, argv[i]);
  if (document.meshList.empty()) fail("no input mesh");
  document.setCurrentMesh(document.meshList.front()->id());

  QPluginLoader loader(QFileInfo(argv[1]).absoluteFilePath());
  auto* filter = qobject_cast<MeshFilterInterface*>(loader.instance());
  if (!filter) fail("not a filter plugin: " + loader.errorString().toStdString());
  GLLogStream log;
  filter->setLog(&log);
  QAction* action = nullptr;
  for (QAction* a : filter->actions())
    if (a->text().toStdString() == filterName) action = a;
  if (!action) fail("the plugin has no filter named " + filterName);

  RichParameterList parameters;
  filter->initParameterSet(action, document, parameters);
  for (++i; i < argc; ++i) setParameter(document, parameters, argv[i]);
  const bool ok = filter->applyFilter(action, document, parameters, nullptr);

  QStringList lines;
  log.print(lines);
  std::vector<std::string> logLines;
  for (const QString& l : lines) logLines.push_back(l.toStdString());
  std::vector<meshmend::JsonObject> layers;
  int index = 0;
  for (MeshModel* m : document.meshList) {
    const std::string path = outFolder + "/" + std::to_string(index++) + ".off";
    writeOff(m->cm, path);
    layers.push_back(
        meshmend::JsonObject().set("label", m->label().toStdString()).set("file", path));
  }
  std::printf("%s\n", meshmend::JsonObject()
                          .set("ok", ok)
                          .set("error", filter->errorMsg().toStdString())
                          .set("log", logLines)
                          .set("layers", layers)
                          .str(true)
                          .c_str());
  return 0;
}
