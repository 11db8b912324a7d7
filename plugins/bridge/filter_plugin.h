// The base of every MeshMend filter plugin: one interface that the plugins
// implement, mapped onto the filter API of the MeshLab they are built for
// (meshlab_host.h). A plugin declares itself with
//
//   class XPlugin : public QObject, public meshmend::bridge::FilterAdapter {
//     Q_OBJECT
//     MESHLAB_PLUGIN_IID_EXPORTER(MESHMEND_FILTER_IID)
//     Q_INTERFACES(MESHMEND_FILTER_INTERFACE)
//
// and implements filterName, pythonFilterName, filterInfo, filterClass, arity,
// preconditions, postconditions, initParameters and apply. `apply` throws
// meshmend errors; the adapter turns them into what the host expects (an
// error message and `false` in 2020.09, an MLException in 2022.02) and hands
// the report published with publishReport back as the filter's result map.
#pragma once

#include <initializer_list>
#include <map>
#include <string>

#include <QAction>
#include <QVariant>

#include "common/base/json.h"
#include "plugins/bridge/meshlab_host.h"

#if MESHMEND_MESHLAB_API == 2022
#define MESHMEND_FILTER_INTERFACE FilterPlugin
#define MESHMEND_FILTER_IID FILTER_PLUGIN_IID
#else
#define MESHMEND_FILTER_INTERFACE MeshFilterInterface
#define MESHMEND_FILTER_IID MESH_FILTER_INTERFACE_IID
#endif

namespace meshmend::bridge {

class FilterAdapter : public MESHMEND_FILTER_INTERFACE {
 public:
  using HostInterface = MESHMEND_FILTER_INTERFACE;
#if MESHMEND_MESHLAB_API == 2022
  using FilterIDType = ActionIDType;
  using Arity = FilterArity;
#else
  using Arity = FILTER_ARITY;
#endif

  // --- what each MeshMend plugin implements, the same for both hosts

  // The stable name under which pymeshlab lists the filter
  // ("meshmend_fill_holes"); its parameters keep their names.
#if MESHMEND_MESHLAB_API == 2022
  QString pythonFilterName(FilterIDType filter) const override = 0;
#else
  virtual QString pythonFilterName(FilterIDType filter) const = 0;
#endif
  virtual FilterClass filterClass(QAction* filter) const = 0;
  virtual Arity arity(QAction* filter) const = 0;
  virtual int preconditions(QAction*) const { return MeshModel::MM_NONE; }
  virtual int postconditions(QAction*) const { return MeshModel::MM_ALL; }
  virtual void initParameters(QAction* filter, MeshDocument& md,
                              RichParameterList& parameters) = 0;
  // Runs the filter; throws meshmend::Error (and std::exception) on failure,
  // having changed nothing in the document.
  virtual void apply(QAction* filter, MeshDocument& md, const RichParameterList& parameters,
                     vcg::CallBackPos* cb) = 0;

  // --- the host's interface, implemented once here
#if MESHMEND_MESHLAB_API == 2022
  using HostInterface::pythonFilterName;
  using HostInterface::initParameterList;
  FilterClass getClass(const QAction* a) const final { return filterClass(mutableAction(a)); }
  FilterArity filterArity(const QAction* a) const final { return arity(mutableAction(a)); }
  int getPreConditions(const QAction* a) const final { return preconditions(mutableAction(a)); }
  int postCondition(const QAction* a) const final { return postconditions(mutableAction(a)); }
  RichParameterList initParameterList(const QAction* a, const MeshDocument& md) final;
  std::map<std::string, QVariant> applyFilter(const QAction* a, const RichParameterList& parameters,
                                              MeshDocument& md, unsigned int& postConditionMask,
                                              vcg::CallBackPos* cb) final;

  // The 2020.09 spelling of the plugin log, used by the shared filter code.
  template <typename... Ts>
  void Log(const char* format, Ts&&... values) const {
    log(format, std::forward<Ts>(values)...);
  }
  void Log(const std::string& text) const { log(text); }
#else
  FilterClass getClass(QAction* a) final { return filterClass(a); }
  FILTER_ARITY filterArity(QAction* a) const final { return arity(a); }
  int getPreConditions(QAction* a) const final { return preconditions(a); }
  int postCondition(QAction* a) const final { return postconditions(a); }
  using HostInterface::initParameterSet;
  void initParameterSet(QAction* a, MeshDocument& md, RichParameterList& parameters) final {
    initParameters(a, md, parameters);
  }
  bool applyFilter(QAction* a, MeshDocument& md, const RichParameterList& parameters,
                   vcg::CallBackPos* cb) final;
#endif

 protected:
  // Registers the plugin's filters: one QAction each, owned by `plugin`.
  void addFilters(QObject* plugin, std::initializer_list<FilterIDType> filters);

  // Writes `report` to the path of the `report_file` parameter (when not
  // empty) and makes it the filter's result (pymeshlab returns it as a dict).
  void publishReport(const RichParameterList& parameters, const JsonObject& report);

 private:
  // The hosts hand actions as const in 2022.02 and mutable in 2020.09; the
  // filters only read them (ID, text).
  static QAction* mutableAction(const QAction* a) { return const_cast<QAction*>(a); }

  JsonObject published_;
};

#if MESHMEND_MESHLAB_API == 2022
// The report as a filter result map: numbers as int (when integral and in
// range) or double, booleans as bool, null as NaN, arrays of numbers as
// Eigen::VectorXd: the types pymeshlab converts to Python. Strings, other
// arrays and objects are left out (pymeshlab would skip each with a warning);
// they are in the report file.
std::map<std::string, QVariant> resultMap(const JsonObject& report);
#endif

}  // namespace meshmend::bridge
