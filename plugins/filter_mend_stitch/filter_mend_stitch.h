// Trimming and stitching (common/stitch.h): "MeshMend: Trim Along Vertex
// Loop", "MeshMend: Stitch Boundaries" and "MeshMend: Close Gaps Between
// Borders".
#pragma once

#include <common/interfaces.h>

class StitchPlugin : public QObject, public MeshFilterInterface {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(MESH_FILTER_INTERFACE_IID)
  Q_INTERFACES(MeshFilterInterface)

 public:
  enum { TRIM_ALONG_LOOP, STITCH_BOUNDARIES, CLOSE_GAPS };

  StitchPlugin();
  QString pluginName() const override { return "MeshMendStitch"; }
  QString filterName(FilterIDType filter) const override;
  QString filterInfo(FilterIDType filter) const override;
  FilterClass getClass(QAction* a) override {
    return ID(a) == STITCH_BOUNDARIES ? MeshFilterInterface::Remeshing
                                      : MeshFilterInterface::Cleaning;
  }
  FILTER_ARITY filterArity(QAction* a) const override {
    return ID(a) == TRIM_ALONG_LOOP ? SINGLE_MESH : VARIABLE;
  }
  int getPreConditions(QAction*) const override { return MeshModel::MM_NONE; }
  int postCondition(QAction*) const override { return MeshModel::MM_ALL; }
  void initParameterSet(QAction*, MeshDocument& md, RichParameterList& parameters) override;
  bool applyFilter(QAction* filter, MeshDocument& md, const RichParameterList& parameters,
                   vcg::CallBackPos* cb) override;

 private:
  void trim(MeshDocument& md, const RichParameterList& parameters, vcg::CallBackPos* cb);
  void stitch(MeshDocument& md, const RichParameterList& parameters, vcg::CallBackPos* cb);
  void closeGaps(MeshDocument& md, const RichParameterList& parameters, vcg::CallBackPos* cb);
};
