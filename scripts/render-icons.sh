#!/usr/bin/env bash
# Renders assets/icons/*.svg into the PNGs the console and the desktop use
# (Qt 6.4 on Debian 12 reads SVG only with the extra qt6-svg plugin, and the
# hicolor theme wants fixed sizes). Run after editing an SVG; commit both.
# Needs rsvg-convert (Debian: librsvg2-bin).
set -euo pipefail
cd "$(dirname "$0")/../assets/icons"
for size in 16 24 32 48 64 128 256; do
  mkdir -p "hicolor/${size}x${size}"
  rsvg-convert -w "$size" -h "$size" simpartner.svg -o "hicolor/${size}x${size}/simpartner.png"
done
for svg in actions/*.svg; do
  png="${svg%.svg}.png"
  rsvg-convert -w 24 -h 24 "$svg" -o "$png"
  rsvg-convert -w 48 -h 48 "$svg" -o "${png%.png}@2x.png"  # Qt picks it on high-DPI screens
done
echo "render-icons: $(ls hicolor/*/simpartner.png actions/*.png | wc -l) PNGs"
# The Qt resource file that bundles what the console shows (ui/CMakeLists.txt).
{
  echo '<!DOCTYPE RCC>'
  echo '<!-- Written by scripts/render-icons.sh: what the console shows, bundled into it. -->'
  echo '<RCC version="1.0">'
  echo '  <qresource prefix="/">'
  for f in hicolor/*/simpartner.png actions/*.png; do echo "    <file>icons/$f</file>"; done | sort -V
  echo '  </qresource>'
  echo '</RCC>'
} > ../assets.qrc
