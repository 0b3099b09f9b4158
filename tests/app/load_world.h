#pragma once
// A world file the test cannot do without: loaded, or the test stops with
// the file's diagnostics.

#include <QtGlobal>

#include "sim/model_loader.h"

namespace sp {

inline WorldModel loadOrFail(const char* file) {
  Diagnostics diag;
  std::optional<WorldModel> w = loadWorld(file, diag);
  if (!w) qFatal("%s", diag.format().c_str());
  return *w;
}

}  // namespace sp
