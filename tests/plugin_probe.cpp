// plugin_probe PLUGIN.so...: loads MeshLab plugins the way MeshLab does
// (QPluginLoader + qobject_cast) and prints, as JSON, each filter's name,
// class, arity and parameters (name and type) as the plugin declares them
// for a document holding one small mesh. Tests use it to check that every
// filter registers and that every sample script lists every parameter.
#include <common/interfaces.h>
#include <common/meshmodel.h>
#include <QApplication>
#include <QDomDocument>
#include <QFileInfo>
#include <QPluginLoader>

#include <cstdio>
#include <string>

#include "common/base/json.h"

int main(int argc, char** argv) {
  qputenv("QT_QPA_PLATFORM", "offscreen");
  QApplication app(argc, argv);
  MeshDocument document;
  MeshModel* model = document.addNewMesh("", "probe");
  auto vi = vcg::tri::Allocator<CMeshO>::AddVertices(model->cm, 3);
  vi[0].P() = Point3m(0, 0, 0);
  vi[1].P() = Point3m(1, 0, 0);
  vi[2].P() = Point3m(0, 1, 0);
  auto fi = vcg::tri::Allocator<CMeshO>::AddFaces(model->cm, 1);
  for (int k = 0; k < 3; ++k) fi->V(k) = &model->cm.vert[k];

  std::vector<meshmend::JsonObject> plugins;
  int failures = 0;
  for (int i = 1; i < argc; ++i) {
    QPluginLoader loader(QFileInfo(argv[i]).absoluteFilePath());
    QObject* instance = loader.instance();
    meshmend::JsonObject entry;
    entry.set("file", QFileInfo(argv[i]).fileName().toStdString());
    if (!instance) {
      entry.set("error", loader.errorString().toStdString());
      ++failures;
      plugins.push_back(entry);
      continue;
    }
    std::vector<meshmend::JsonObject> filters;
    if (auto* filter = qobject_cast<MeshFilterInterface*>(instance)) {
      for (QAction* action : filter->actions()) {
        RichParameterList parameters;
        filter->initParameterSet(action, document, parameters);
        std::vector<meshmend::JsonObject> params;
        for (const RichParameter& p : parameters) {
          // The <Param> element MeshLab itself writes into a script (default value).
          QDomDocument doc;
          doc.appendChild(p.fillToXMLDocument(doc, true));
          params.push_back(meshmend::JsonObject()
                               .set("name", p.name().toStdString())
                               .set("type", p.stringType().toStdString())
                               .set("tooltip", p.toolTip().toStdString())
                               .set("xml", doc.toString(-1).trimmed().toStdString()));
        }
        filters.push_back(meshmend::JsonObject()
                              .set("name", action->text().toStdString())
                              .set("class", int(filter->getClass(action)))
                              .set("arity", int(filter->filterArity(action)))
                              .set("info", filter->filterInfo(action).toStdString())
                              .set("parameters", params));
      }
    }
    if (auto* io = qobject_cast<MeshIOInterface*>(instance)) {
      std::vector<std::string> formats;
      for (const auto& f : io->importFormats())
        for (const QString& e : f.extensions) formats.push_back(e.toStdString());
      entry.set("import_formats", formats);
    }
    entry.set("filters", filters);
    plugins.push_back(entry);
  }
  std::printf("%s\n", meshmend::JsonObject().set("plugins", plugins).str(true).c_str());
  return failures ? 1 : 0;
}
