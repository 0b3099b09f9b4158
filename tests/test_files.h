#pragma once
// Writing small input files for tests.

#include <QByteArray>
#include <QTemporaryDir>

#include <fstream>
#include <string>

namespace sp::test {

/// Writes `content` to `name` in `dir` (bytes as given) and returns its path.
inline std::string writeFile(const QTemporaryDir& dir, const char* name, const QByteArray& content) {
  const std::string path = dir.filePath(name).toStdString();
  std::ofstream out(path, std::ios::binary);
  out.write(content.constData(), content.size());
  return path;
}

}  // namespace sp::test
