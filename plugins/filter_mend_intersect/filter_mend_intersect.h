// Intersections between and within layers: "MeshMend: Select Intersecting
// Faces" and "MeshMend: Intersect and Split Layers".
#pragma once

#include "common/repair/output_stage.h"
#include "common/repair/split/split.h"
#include "plugins/bridge/filter_plugin.h"

class IntersectPlugin : public QObject, public meshmend::bridge::FilterAdapter {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(MESHMEND_FILTER_IID)
  Q_INTERFACES(MESHMEND_FILTER_INTERFACE)

 public:
  enum { SELECT_INTERSECTING, INTERSECT_AND_SPLIT };

  IntersectPlugin();
  QString pluginName() const override { return "MeshMendIntersect"; }
  QString filterName(FilterIDType filter) const override;
  QString pythonFilterName(FilterIDType filter) const override;
  QString filterInfo(FilterIDType filter) const override;
  FilterClass filterClass(QAction* a) const override {
    return ID(a) == SELECT_INTERSECTING ? Selection : Remeshing;
  }
  Arity arity(QAction*) const override { return VARIABLE; }
  int preconditions(QAction*) const override { return MeshModel::MM_NONE; }
  int postconditions(QAction* a) const override {
    return ID(a) == SELECT_INTERSECTING ? int(MeshModel::MM_FACEFLAGSELECT)
                                        : int(MeshModel::MM_ALL);
  }
  void initParameters(QAction*, MeshDocument& md, RichParameterList& parameters) override;
  void apply(QAction* filter, MeshDocument& md, const RichParameterList& parameters,
             vcg::CallBackPos* cb) override;

 private:
  void selectIntersecting(MeshDocument& md, const RichParameterList& parameters,
                          vcg::CallBackPos* cb);
  void intersectAndSplit(MeshDocument& md, const RichParameterList& parameters,
                         vcg::CallBackPos* cb);
  void logStored(const meshmend::StoredOutput& stored, const meshmend::SplitResult& r);
  void explainRemaining(const meshmend::SplitResult& r, std::size_t others, bool merge);
};
