// OBJ importer for MeshLab 2020.09 that replaces the host's, which aborts on
// valid files. Reading is done by the core (common/obj_reader.h).
#pragma once

#include <common/interfaces.h>

class ObjImportPlugin : public QObject, public MeshIOInterface {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(MESH_IO_INTERFACE_IID)
  Q_INTERFACES(MeshIOInterface)

 public:
  QString pluginName() const override { return "MeshMendObjImport"; }
  QList<Format> importFormats() const override;
  QList<Format> exportFormats() const override { return {}; }
  void GetExportMaskCapability(QString&, int& capability, int& defaultBits) const override {
    capability = defaultBits = 0;
  }
  bool open(const QString& format, const QString& fileName, MeshModel& m, int& mask,
            const RichParameterList& parameters, vcg::CallBackPos* cb = nullptr,
            QWidget* parent = nullptr) override;
  bool save(const QString&, const QString&, MeshModel&, const int, const RichParameterList&,
            vcg::CallBackPos* = nullptr, QWidget* = nullptr) override {
    errorMessage = "MeshMend's OBJ plugin only imports; MeshLab's own exporter writes OBJ";
    return false;
  }
};
