// Runs MeshMend's MeshLab 2022.02 plugins the way pymeshlab 2022.2 runs a
// plugin given to pymeshlab.load_plugin, without pymeshlab: through
// libmeshlab-common 2022.02 (double precision) and its PluginManager and
// pymeshlab::FunctionSet.
//
//   meshlab2022_host list PLUGIN...
//       loads and checks each plugin; prints every filter with its python
//       name and default parameters (computed on pymeshlab's 1x1x1 cube).
//   meshlab2022_host apply PLUGIN... [--mesh FILE]... --filter NAME [--param NAME=VALUE]...
//                    [--filter NAME [--param NAME=VALUE]...]... [--save DIR]
//       opens the meshes as layers 0, 1, ... of a MeshDocument and applies
//       the filters in order (a script), each by its python name with the
//       parameters that follow it set by their python names (an AbsPerc value
//       may end in %); prints each filter's returned map and the layers.
//       --save writes every layer to DIR/<id>.ply (binary, double).
//
// Prints one JSON object. Exit status: 0 all applied, 1 a filter raised an
// MLException (its step's "error"; later steps do not run), 2 the plugins or
// arguments were refused.
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include <QCoreApplication>
#include <QDir>
#include <QFileInfo>

#include <common/globals.h>
#include <common/ml_document/mesh_document.h>
#include <common/mlexception.h>
#include <common/plugins/plugin_manager.h>
#include <common/python/function_set.h>
#include <vcg/complex/algorithms/clean.h>
#include <vcg/complex/algorithms/update/bounding.h>
#include <vcg/complex/algorithms/update/normal.h>
#include <vcg/complex/algorithms/update/selection.h>
#include <wrap/gl/glu_tesselator.h>  // the OFF reader triangulates polygons with it
#include <wrap/io_trimesh/export_ply.h>
#include <wrap/io_trimesh/import_off.h>
#include <wrap/io_trimesh/import_ply.h>
#include <wrap/io_trimesh/import_stl.h>

#include "common/json.h"

namespace {

using meshmend::JsonObject;

[[noreturn]] void refuse(const std::string& message) {
  std::printf("%s\n", JsonObject().set("refused", message).str(true).c_str());
  std::exit(2);
}

bool progress(int, const char*) {
  return true;
}

// The plugin files, loaded and checked by the PluginManager
// (PluginManager::loadPlugin runs checkPlugin: API, precision, version).
std::vector<JsonObject> loadPlugins(PluginManager& pm, const std::vector<std::string>& files) {
  std::vector<JsonObject> loaded;
  for (const std::string& file : files) {
    const QString path = QFileInfo(QString::fromStdString(file)).absoluteFilePath();
    try {
      const MeshLabPluginType type = PluginManager::checkPlugin(path);
      MeshLabPlugin* plugin = pm.loadPlugin(path);
      loaded.push_back(JsonObject()
                           .set("file", QFileInfo(path).fileName().toStdString())
                           .set("name", plugin->pluginName().toStdString())
                           .set("filter_plugin", type.isFilterPlugin())
                           .set("meshlab_version", plugin->getMLVersion().first)
                           .set("double_precision", plugin->getMLVersion().second));
    } catch (const MLException& e) {
      refuse(QFileInfo(path).fileName().toStdString() + ": " + e.what());
    }
  }
  return loaded;
}

// A parameter's default as pymeshlab documents it.
JsonObject parameterJson(const pymeshlab::FunctionParameter& p) {
  JsonObject out;
  out.set("name", p.pythonName().toStdString()).set("type", p.meshlabTypeString().toStdString());
  const Value& v = p.defaultValue();
  if (v.isBool())
    out.set("default", v.getBool());
  else if (v.isInt())
    out.set("default", v.getInt());
  else if (v.isFloat())
    out.set("default", double(v.getFloat()));
  else if (v.isString())
    out.set("default", v.getString().toStdString());
  return out;
}

int list(PluginManager& pm, const std::vector<JsonObject>& loaded) {
  const pymeshlab::FunctionSet functions(pm);
  std::vector<JsonObject> filters;
  for (FilterPlugin* fp : pm.filterPluginIterator())
    for (QAction* action : fp->actions()) {
      const QString name = fp->pythonFilterName(action);
      const pymeshlab::Function& f = functions.filterFunction(name);
      std::vector<JsonObject> parameters;
      for (const pymeshlab::FunctionParameter& p : f) parameters.push_back(parameterJson(p));
      filters.push_back(JsonObject()
                            .set("python_name", name.toStdString())
                            .set("name", fp->filterName(action).toStdString())
                            .set("plugin", fp->pluginName().toStdString())
                            .set("class", int(fp->getClass(action)))
                            .set("arity", int(fp->filterArity(action)))
                            .set("parameters", parameters));
    }
  std::printf("%s\n",
              JsonObject().set("plugins", loaded).set("filters", filters).str(true).c_str());
  return 0;
}

// Reads a PLY, OFF or STL file into `m` (vcglib's readers, as MeshLab's
// io_base uses); refuses other formats and unreadable files.
void readMesh(MeshModel& m, const std::string& file) {
  const QString ext = QFileInfo(QString::fromStdString(file)).suffix().toLower();
  int mask = 0, error = 0;
  std::string message;
  if (ext == "ply") {
    vcg::tri::io::ImporterPLY<CMeshO>::LoadMask(file.c_str(), mask);
    m.enable(mask);
    error = vcg::tri::io::ImporterPLY<CMeshO>::Open(m.cm, file.c_str(), mask);
    if (error) message = vcg::tri::io::ImporterPLY<CMeshO>::ErrorMsg(error);
  } else if (ext == "off") {
    vcg::tri::io::ImporterOFF<CMeshO>::LoadMask(file.c_str(), mask);
    m.enable(mask);
    error = vcg::tri::io::ImporterOFF<CMeshO>::Open(m.cm, file.c_str(), mask);
    if (error) message = vcg::tri::io::ImporterOFF<CMeshO>::ErrorMsg(error);
  } else if (ext == "stl") {
    vcg::tri::io::ImporterSTL<CMeshO>::LoadMask(file.c_str(), mask);
    m.enable(mask);
    error = vcg::tri::io::ImporterSTL<CMeshO>::Open(m.cm, file.c_str(), mask);
    if (error) message = vcg::tri::io::ImporterSTL<CMeshO>::ErrorMsg(error);
  } else {
    refuse(file + ": the host reads PLY, OFF and STL");
  }
  if (error) refuse(file + ": " + message);
  if (!(mask & vcg::tri::io::Mask::IOM_VERTNORMAL))
    vcg::tri::UpdateNormal<CMeshO>::PerVertexAngleWeighted(m.cm);
}

// Opens a mesh file as a new layer as pymeshlab's loader leaves it: normals,
// bounding box, no NaN vertices or degenerate faces, compact vectors.
void openLayer(MeshDocument& md, const std::string& file) {
  const QFileInfo info(QString::fromStdString(file));
  if (!info.isFile()) refuse("no such mesh file: " + file);
  MeshModel* m = md.addNewMesh(info.absoluteFilePath(), info.fileName(), true);
  readMesh(*m, file);
  vcg::tri::UpdateNormal<CMeshO>::PerFaceNormalized(m->cm);
  vcg::tri::UpdateBounding<CMeshO>::Box(m->cm);
  vcg::tri::Clean<CMeshO>::RemoveDegenerateVertex(m->cm);
  vcg::tri::Clean<CMeshO>::RemoveDegenerateFace(m->cm);
  vcg::tri::Allocator<CMeshO>::CompactEveryVector(m->cm);
}

// Sets one parameter from text, by the parameter's type, as pymeshlab does
// from a keyword argument.
void setParameter(RichParameterList& rpl, const pymeshlab::Function& f,
                  const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos) refuse("--param takes NAME=VALUE, got '" + assignment + "'");
  const QString name = QString::fromStdString(assignment.substr(0, eq));
  const std::string text = assignment.substr(eq + 1);
  if (!f.contains(name))
    refuse("filter " + f.pythonFunctionName().toStdString() + " has no parameter " +
           name.toStdString());
  const pymeshlab::FunctionParameter& fp = f.getFilterFunctionParameter(name);
  RichParameter& p = rpl.getParameterByName(fp.meshlabName());
  const QString type = fp.meshlabTypeString();
  try {
    if (type == "RichBool") {
      if (text != "true" && text != "false") refuse(name.toStdString() + " takes true or false");
      p.setValue(BoolValue(text == "true"));
    } else if (type == "RichInt" || type == "RichMesh") {
      p.setValue(IntValue(std::stoi(text)));
    } else if (type == "RichFloat") {
      p.setValue(FloatValue(float(std::stod(text))));
    } else if (type == "RichAbsPerc") {
      const RichAbsPerc& abs = dynamic_cast<const RichAbsPerc&>(p);
      double value = std::stod(text);
      if (!text.empty() && text.back() == '%') value = abs.min + (abs.max - abs.min) * value / 100;
      p.setValue(FloatValue(float(value)));
    } else if (type == "RichEnum") {
      const RichEnum& e = dynamic_cast<const RichEnum&>(p);
      int index = e.enumvalues.indexOf(QString::fromStdString(text));
      if (index < 0) index = std::stoi(text);
      if (index < 0 || index >= e.enumvalues.size())
        refuse(name.toStdString() + ": no choice '" + text + "'");
      p.setValue(IntValue(index));
    } else if (type == "RichString") {
      p.setValue(StringValue(QString::fromStdString(text)));
    } else {
      refuse(name.toStdString() + ": parameter type " + type.toStdString() + " not supported here");
    }
  } catch (const std::logic_error&) {  // std::stoi / std::stod
    refuse(name.toStdString() + ": '" + text + "' is not a " + type.toStdString() + " value");
  }
}

// One entry of the returned map: its QVariant type and value. pymeshlab
// 2022.2 converts int, double, float, bool and Eigen::VectorXd to Python and
// skips the other types with a warning.
void setResult(JsonObject& values, JsonObject& types, const std::string& key, const QVariant& v) {
  const std::string type = v.typeName() ? v.typeName() : "invalid";
  types.set(key, type);
  if (type == "int")
    values.set(key, v.toInt());
  else if (type == "double" || type == "float")
    values.set(key, v.toDouble());
  else if (type == "bool")
    values.set(key, v.toBool());
  else if (v.canConvert<Eigen::VectorXd>()) {
    const Eigen::VectorXd x = v.value<Eigen::VectorXd>();
    values.set(key, std::vector<double>(x.data(), x.data() + x.size()));
  } else if (type == "QString")
    values.set(key, v.toString().toStdString());
  else
    values.setNull(key);
}

std::vector<JsonObject> layersJson(MeshDocument& md) {
  std::vector<JsonObject> layers;
  for (MeshModel& m : md.meshIterator())
    layers.push_back(JsonObject()
                         .set("id", int(m.id()))
                         .set("label", m.label().toStdString())
                         .set("current", &m == md.mm())
                         .set("visible", m.isVisible())
                         .set("vertices", m.cm.vn)
                         .set("faces", m.cm.fn)
                         .set("edges", m.cm.en)
                         .set("selected_faces", m.cm.sfn)
                         .set("selected_vertices", m.cm.svn));
  return layers;
}

struct Step {
  std::string filter;
  std::vector<std::string> assignments;
};

// Applies one filter as pymeshlab's MeshSet.apply_filter does; false when
// the filter raised an MLException.
bool applyStep(PluginManager& pm, const pymeshlab::FunctionSet& functions, MeshDocument& md,
               const Step& step, JsonObject& out) {
  const QString name = QString::fromStdString(step.filter);
  if (!functions.containsFilterFunction(name)) refuse("no filter named " + step.filter);
  const pymeshlab::Function& f = functions.filterFunction(name);

  // The plugin and action that define the filter (pymeshlab's pluginFromFilterName).
  FilterPlugin* plugin = nullptr;
  QAction* action = nullptr;
  for (FilterPlugin* fp : pm.filterPluginIterator())
    for (QAction* a : fp->actions())
      if (fp->filterName(a) == f.meshlabFunctionName()) plugin = fp, action = a;
  if (!plugin) refuse("no plugin defines " + step.filter);

  RichParameterList rpl = plugin->initParameterList(action, md);
  for (const std::string& a : step.assignments) setParameter(rpl, f, a);
  out.set("filter", step.filter);
  try {
    if (md.mm()) md.mm()->updateDataMask(plugin->getRequirements(action));
    unsigned int postConditionMask = MeshModel::MM_UNKNOWN;
    const std::map<std::string, QVariant> result =
        plugin->applyFilter(action, rpl, md, postConditionMask, &progress);
    for (MeshModel& m : md.meshIterator()) {
      m.cm.svn = int(vcg::tri::UpdateSelection<CMeshO>::VertexCount(m.cm));
      m.cm.sfn = int(vcg::tri::UpdateSelection<CMeshO>::FaceCount(m.cm));
    }
    JsonObject values, types;
    for (const auto& [key, value] : result) setResult(values, types, key, value);
    out.set("result", values).set("result_types", types);
    return true;
  } catch (const MLException& e) {
    out.set("error", std::string(e.what()));
    return false;
  }
}

int apply(PluginManager& pm, const std::vector<JsonObject>& loaded,
          const std::vector<std::string>& meshes, const std::vector<Step>& steps,
          const std::string& saveDir) {
  const pymeshlab::FunctionSet functions(pm);
  MeshDocument md;
  for (const std::string& mesh : meshes) openLayer(md, mesh);
  for (FilterPlugin* fp : pm.filterPluginIterator()) fp->setLog(&md.Log);

  std::vector<JsonObject> done;
  int status = 0;
  for (const Step& step : steps) {
    JsonObject out;
    const bool ok = applyStep(pm, functions, md, step, out);
    done.push_back(out);
    if (!ok) {
      status = 1;
      break;
    }
  }
  std::vector<std::string> log;
  for (const auto& line : md.Log.logStringList()) log.push_back(line.second.toStdString());
  if (!saveDir.empty()) {
    QDir().mkpath(QString::fromStdString(saveDir));
    for (MeshModel& m : md.meshIterator()) {
      const std::string path = saveDir + "/" + std::to_string(m.id()) + ".ply";
      vcg::tri::io::ExporterPLY<CMeshO>::Save(m.cm, path.c_str(), vcg::tri::io::Mask::IOM_NONE,
                                              true);
    }
  }
  std::printf("%s\n", JsonObject()
                          .set("plugins", loaded)
                          .set("steps", done)
                          .set("layers", layersJson(md))
                          .set("log", log)
                          .str(true)
                          .c_str());
  return status;
}

}  // namespace

int main(int argc, char** argv) {
  QCoreApplication app(argc, argv);
  if (argc < 3) refuse("usage: meshlab2022_host list|apply PLUGIN... [options] (see the source)");
  const std::string command = argv[1];
  std::vector<std::string> plugins, meshes;
  std::vector<Step> steps;
  std::string saveDir;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) refuse(arg + " needs a value");
      return argv[++i];
    };
    if (arg == "--filter") {
      steps.push_back({next(), {}});
    } else if (arg == "--param") {
      if (steps.empty()) refuse("--param before any --filter");
      steps.back().assignments.push_back(next());
    } else if (arg == "--mesh") {
      meshes.push_back(next());
    } else if (arg == "--save") {
      saveDir = next();
    } else if (arg.rfind("--", 0) == 0) {
      refuse("unknown option " + arg);
    } else {
      plugins.push_back(arg);
    }
  }
  PluginManager& pm = meshlab::pluginManagerInstance();
  const std::vector<JsonObject> loaded = loadPlugins(pm, plugins);
  if (command == "list") return list(pm, loaded);
  if (command == "apply" && !steps.empty()) return apply(pm, loaded, meshes, steps, saveDir);
  refuse("usage: meshlab2022_host list PLUGIN... | apply PLUGIN... --filter NAME ...");
}
