// "MeshMend: Fill Holes (Feature Preserving)": patches that follow the shape
// around each hole (common/holes.h), in place.
#pragma once

#include <common/interfaces.h>

class HolesPlugin : public QObject, public MeshFilterInterface {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(MESH_FILTER_INTERFACE_IID)
  Q_INTERFACES(MeshFilterInterface)

 public:
  enum { FILL_HOLES };

  HolesPlugin();
  QString pluginName() const override { return "MeshMendHoles"; }
  QString filterName(FilterIDType filter) const override;
  QString filterInfo(FilterIDType filter) const override;
  FilterClass getClass(QAction*) override { return MeshFilterInterface::Remeshing; }
  FILTER_ARITY filterArity(QAction*) const override { return SINGLE_MESH; }
  int getPreConditions(QAction*) const override { return MeshModel::MM_NONE; }
  int postCondition(QAction*) const override { return MeshModel::MM_ALL; }
  void initParameterSet(QAction*, MeshModel& m, RichParameterList& parameters) override;
  bool applyFilter(QAction* filter, MeshDocument& md, const RichParameterList& parameters,
                   vcg::CallBackPos* cb) override;
};
