// "MeshMend: Inspect Mesh Defects": the defect report of the current layer.
#pragma once

#include <common/interfaces.h>

class InspectPlugin : public QObject, public MeshFilterInterface {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(MESH_FILTER_INTERFACE_IID)
  Q_INTERFACES(MeshFilterInterface)

 public:
  enum { INSPECT_DEFECTS };

  InspectPlugin();
  QString pluginName() const override { return "MeshMendInspect"; }
  QString filterName(FilterIDType filter) const override;
  QString filterInfo(FilterIDType filter) const override;
  FilterClass getClass(QAction*) override { return MeshFilterInterface::Measure; }
  FILTER_ARITY filterArity(QAction*) const override { return SINGLE_MESH; }
  int getPreConditions(QAction*) const override { return MeshModel::MM_NONE; }
  int postCondition(QAction*) const override;
  void initParameterSet(QAction*, MeshModel& m, RichParameterList& parameters) override;
  bool applyFilter(QAction* filter, MeshDocument& md, const RichParameterList& parameters,
                   vcg::CallBackPos* cb) override;
};
