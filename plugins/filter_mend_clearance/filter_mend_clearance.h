// Minimum clearance between surfaces: "MeshMend: Measure Clearance" and
// "MeshMend: Enforce Minimum Clearance" (common/clearance.h).
#pragma once

#include <common/interfaces.h>

class ClearancePlugin : public QObject, public MeshFilterInterface {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(MESH_FILTER_INTERFACE_IID)
  Q_INTERFACES(MeshFilterInterface)

 public:
  enum { MEASURE_CLEARANCE, ENFORCE_CLEARANCE };

  ClearancePlugin();
  QString pluginName() const override { return "MeshMendClearance"; }
  QString filterName(FilterIDType filter) const override;
  QString filterInfo(FilterIDType filter) const override;
  // Enforcing moves vertices and keeps the connectivity, like MeshLab's
  // smoothing and displacement filters: it belongs with them, not with the
  // filters that re-triangulate (Remeshing).
  FilterClass getClass(QAction* a) override {
    return ID(a) == MEASURE_CLEARANCE ? MeshFilterInterface::Measure
                                      : MeshFilterInterface::Smoothing;
  }
  FILTER_ARITY filterArity(QAction*) const override { return VARIABLE; }
  int getPreConditions(QAction*) const override { return MeshModel::MM_NONE; }
  int postCondition(QAction* a) const override {
    return ID(a) == MEASURE_CLEARANCE
               ? int(MeshModel::MM_VERTQUALITY | MeshModel::MM_FACEFLAGSELECT)
               : int(MeshModel::MM_VERTCOORD | MeshModel::MM_FACENORMAL);
  }
  void initParameterSet(QAction*, MeshDocument& md, RichParameterList& parameters) override;
  bool applyFilter(QAction* filter, MeshDocument& md, const RichParameterList& parameters,
                   vcg::CallBackPos* cb) override;

 private:
  void measure(MeshDocument& md, const RichParameterList& parameters, vcg::CallBackPos* cb);
  void enforce(MeshDocument& md, const RichParameterList& parameters, vcg::CallBackPos* cb);
};
