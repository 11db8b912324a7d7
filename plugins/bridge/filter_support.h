// What every MeshMend plugin needs around a core call: strings, progress,
// errors that leave the document untouched, the report file, and notes about
// what MeshLab's importer did to a layer.
#pragma once

#include <exception>
#include <new>
#include <string>
#include <vector>

#include <QString>

#include "common/base/errors.h"
#include "common/base/json.h"
#include "common/base/progress.h"
#include "plugins/bridge/meshlab_host.h"

namespace meshmend::bridge {

inline std::string toStd(const QString& s) {
  return s.toStdString();
}
inline QString toQ(const std::string& s) {
  return QString::fromStdString(s);
}

// The layer's name as users see it in the layer dialog, quoted.
inline std::string layerName(const MeshModel& m) {
  return "layer '" + toStd(m.label()) + "'";
}

// The default "second layer" of a two-layer filter: the first layer that
// is not the current one (the current one when it is alone).
inline MeshModel* layerOtherThanCurrent(MeshDocument& md) {
  for (MeshModel* m : layersOf(md))
    if (m != md.mm()) return m;
  return md.mm();
}

// MeshLab's progress callback as a core Progress (null callback: no reports).
inline Progress progressFrom(vcg::CallBackPos* cb) {
  return [cb](int percent, const char* stage) { return cb ? cb(percent, stage) : true; };
}

// Runs `body`, which must compute everything first and change the document
// only at its end. Errors become `errorMessage` (the GUI shows it) and are
// also logged through `log` (meshlabserver prints only the log), and the
// result is false.
template <class Body, class Log>
bool guarded(QString& errorMessage, Body&& body, Log&& log) {
  try {
    body();
    return true;
  } catch (const meshmend::CancelledError& e) {
    errorMessage = "cancelled: the layers were not changed";
  } catch (const meshmend::Error& e) {
    errorMessage = QString::fromUtf8(e.what());
  } catch (const std::bad_alloc&) {
    errorMessage = "out of memory: the mesh is too large for this machine's memory";
  } catch (const std::exception& e) {
    errorMessage = QString("internal error: ") + e.what() +
                   " (please report it with the input mesh); the layer was not changed";
  }
  log("MeshMend error: " + errorMessage.toStdString());
  return false;
}

// Writes `report` to `path` when it is not empty (throws InvalidInputError
// with the path when it cannot be written).
void writeReport(const QString& path, const JsonObject& report);

// What MeshLab's importer did to a layer, found by comparing the vertex and
// face counts in the file's header (OFF, PLY, STL, OBJ) with the layer's:
// triangulated polygons, converted triangle strips, removed degenerate faces,
// vertices of STL facets. Empty when the counts agree or the file is not known.
struct ImportNotes {
  long file_vertices = -1;  // -1: unknown
  long file_faces = -1;
  std::vector<std::string> notes;
};
ImportNotes importNotes(const MeshModel& model);

}  // namespace meshmend::bridge
