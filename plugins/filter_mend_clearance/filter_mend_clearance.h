// Minimum clearance between surfaces: "MeshMend: Measure Clearance" and
// "MeshMend: Enforce Minimum Clearance" (common/clearance.h).
#pragma once

#include "plugins/bridge/filter_plugin.h"

class ClearancePlugin : public QObject, public meshmend::bridge::FilterAdapter {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(MESHMEND_FILTER_IID)
  Q_INTERFACES(MESHMEND_FILTER_INTERFACE)

 public:
  enum { MEASURE_CLEARANCE, ENFORCE_CLEARANCE };

  ClearancePlugin();
  QString pluginName() const override { return "MeshMendClearance"; }
  QString filterName(FilterIDType filter) const override;
  QString pythonFilterName(FilterIDType filter) const override;
  QString filterInfo(FilterIDType filter) const override;
  // Enforcing moves vertices and keeps the connectivity, like MeshLab's
  // smoothing and displacement filters: it belongs with them, not with the
  // filters that re-triangulate (Remeshing).
  FilterClass filterClass(QAction* a) const override {
    return ID(a) == MEASURE_CLEARANCE ? Measure : Smoothing;
  }
  Arity arity(QAction*) const override { return VARIABLE; }
  int preconditions(QAction*) const override { return MeshModel::MM_NONE; }
  int postconditions(QAction* a) const override {
    return ID(a) == MEASURE_CLEARANCE
               ? int(MeshModel::MM_VERTQUALITY | MeshModel::MM_FACEFLAGSELECT)
               : int(MeshModel::MM_VERTCOORD | MeshModel::MM_FACENORMAL);
  }
  void initParameters(QAction*, MeshDocument& md, RichParameterList& parameters) override;
  void apply(QAction* filter, MeshDocument& md, const RichParameterList& parameters,
             vcg::CallBackPos* cb) override;

 private:
  void measure(MeshDocument& md, const RichParameterList& parameters, vcg::CallBackPos* cb);
  void enforce(MeshDocument& md, const RichParameterList& parameters, vcg::CallBackPos* cb);
};
