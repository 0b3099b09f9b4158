#pragma once
// The console's icons, from assets/ (bundled as a Qt resource: nothing is
// read from the checkout at run time). Sources are SVG; the PNGs beside them
// are rendered by scripts/render-icons.sh (Qt 6.4 reads SVG only with an
// extra plugin).

#include <QIcon>

namespace sp {

/// The application's icon, every size the desktop uses.
QIcon appIcon();

/// An action's icon by its file name in assets/icons/actions without
/// extension ("play", "estop", "brush-raise"); a null icon (and a warning
/// on stderr) for a name with no file, so a typo shows as a missing icon.
QIcon actionIcon(const QString& name);

}  // namespace sp
