// Surface patches after intersect-and-split: "MeshMend: Paint Surface
// Patches", "MeshMend: Select Patches" and "MeshMend: Remove Patches".
#pragma once

#include "plugins/bridge/filter_plugin.h"

class PatchesPlugin : public QObject, public meshmend::bridge::FilterAdapter {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(MESHMEND_FILTER_IID)
  Q_INTERFACES(MESHMEND_FILTER_INTERFACE)

 public:
  enum { PAINT_PATCHES, SELECT_PATCHES, REMOVE_PATCHES };

  PatchesPlugin();
  QString pluginName() const override { return "MeshMendPatches"; }
  QString filterName(FilterIDType filter) const override;
  QString pythonFilterName(FilterIDType filter) const override;
  QString filterInfo(FilterIDType filter) const override;
  FilterClass filterClass(QAction* a) const override;
  Arity arity(QAction*) const override { return VARIABLE; }
  int preconditions(QAction*) const override { return MeshModel::MM_NONE; }
  int postconditions(QAction* a) const override;
  void initParameters(QAction*, MeshDocument& md, RichParameterList& parameters) override;
  void apply(QAction* filter, MeshDocument& md, const RichParameterList& parameters,
             vcg::CallBackPos* cb) override;

 private:
  void paint(MeshDocument& md, const RichParameterList& parameters, vcg::CallBackPos* cb);
  void select(MeshDocument& md, const RichParameterList& parameters, vcg::CallBackPos* cb);
  void remove(MeshDocument& md, const RichParameterList& parameters, vcg::CallBackPos* cb);
};
