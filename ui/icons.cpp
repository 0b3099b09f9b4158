#include "ui/icons.h"

#include <QFile>
#include <QtGlobal>

// Outside any namespace, as Q_INIT_RESOURCE requires. The resource lives in
// a static library, so nothing would pull it in without this call.
static void initAssets() { Q_INIT_RESOURCE(assets); }

namespace sp {
namespace {

void ensureAssets() {
  static const bool once = (initAssets(), true);
  (void)once;
}

}  // namespace

QIcon appIcon() {
  ensureAssets();
  QIcon icon;
  for (int size : {16, 24, 32, 48, 64, 128, 256})
    icon.addFile(QStringLiteral(":/icons/hicolor/%1x%1/simpartner.png").arg(size), QSize(size, size));
  return icon;
}

QIcon actionIcon(const QString& name) {
  ensureAssets();
  const QString path = QStringLiteral(":/icons/actions/%1.png").arg(name);
  if (!QFile::exists(path)) {
    qWarning("no icon %s", qPrintable(path));
    return {};
  }
  return QIcon(path);  // picks up name@2x.png for high-DPI screens
}

}  // namespace sp
