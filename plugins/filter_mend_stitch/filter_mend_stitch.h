// Trimming and stitching (common/stitch.h): "MeshMend: Trim Along Vertex
// Loop", "MeshMend: Stitch Boundaries" and "MeshMend: Close Gaps Between
// Borders".
#pragma once

#include "plugins/bridge/filter_plugin.h"

class StitchPlugin : public QObject, public meshmend::bridge::FilterAdapter {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(MESHMEND_FILTER_IID)
  Q_INTERFACES(MESHMEND_FILTER_INTERFACE)

 public:
  enum { TRIM_ALONG_LOOP, STITCH_BOUNDARIES, CLOSE_GAPS };

  StitchPlugin();
  QString pluginName() const override { return "MeshMendStitch"; }
  QString filterName(FilterIDType filter) const override;
  QString pythonFilterName(FilterIDType filter) const override;
  QString filterInfo(FilterIDType filter) const override;
  FilterClass filterClass(QAction* a) const override {
    return ID(a) == STITCH_BOUNDARIES ? Remeshing : Cleaning;
  }
  Arity arity(QAction* a) const override {
    return ID(a) == TRIM_ALONG_LOOP ? SINGLE_MESH : VARIABLE;
  }
  int preconditions(QAction*) const override { return MeshModel::MM_NONE; }
  int postconditions(QAction*) const override { return MeshModel::MM_ALL; }
  void initParameters(QAction*, MeshDocument& md, RichParameterList& parameters) override;
  void apply(QAction* filter, MeshDocument& md, const RichParameterList& parameters,
             vcg::CallBackPos* cb) override;

 private:
  void trim(MeshDocument& md, const RichParameterList& parameters, vcg::CallBackPos* cb);
  void stitch(MeshDocument& md, const RichParameterList& parameters, vcg::CallBackPos* cb);
  void closeGaps(MeshDocument& md, const RichParameterList& parameters, vcg::CallBackPos* cb);
};
