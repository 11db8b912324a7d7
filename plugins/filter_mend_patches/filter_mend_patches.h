// Surface patches after intersect-and-split: "MeshMend: Paint Surface
// Patches", "MeshMend: Select Patches" and "MeshMend: Remove Patches".
#pragma once

#include <common/interfaces.h>

class PatchesPlugin : public QObject, public MeshFilterInterface {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(MESH_FILTER_INTERFACE_IID)
  Q_INTERFACES(MeshFilterInterface)

 public:
  enum { PAINT_PATCHES, SELECT_PATCHES, REMOVE_PATCHES };

  PatchesPlugin();
  QString pluginName() const override { return "MeshMendPatches"; }
  QString filterName(FilterIDType filter) const override;
  QString filterInfo(FilterIDType filter) const override;
  FilterClass getClass(QAction* a) override;
  FILTER_ARITY filterArity(QAction*) const override { return VARIABLE; }
  int getPreConditions(QAction*) const override { return MeshModel::MM_NONE; }
  int postCondition(QAction* a) const override;
  void initParameterSet(QAction*, MeshDocument& md, RichParameterList& parameters) override;
  bool applyFilter(QAction* filter, MeshDocument& md, const RichParameterList& parameters,
                   vcg::CallBackPos* cb) override;

 private:
  void paint(MeshDocument& md, const RichParameterList& parameters, vcg::CallBackPos* cb);
  void select(MeshDocument& md, const RichParameterList& parameters, vcg::CallBackPos* cb);
  void remove(MeshDocument& md, const RichParameterList& parameters, vcg::CallBackPos* cb);
};
