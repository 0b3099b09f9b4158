#pragma once
// What of a dock or of the status bar an operator cannot read at the
// window's size, measured by the widgets themselves (their geometry and
// their font's advance), as "what: why" lines; empty when all is whole.
// Issue 59: "a screenshot test at 1280x800 checks that no label ... is
// clipped or elided".

#include <QAbstractScrollArea>
#include <QLabel>
#include <QPlainTextEdit>
#include <QPushButton>
#include <QSlider>
#include <QStatusBar>
#include <QStringList>
#include <QTableWidget>
#include <QTextDocument>
#include <QTreeWidget>

namespace sp::test {

inline QString widgetName(QWidget* w) {
  if (auto* l = qobject_cast<QLabel*>(w)) return QStringLiteral("label '%1'").arg(l->text().left(40));
  if (auto* b = qobject_cast<QAbstractButton*>(w)) return QStringLiteral("button '%1'").arg(b->text());
  return QString::fromLatin1(w->metaObject()->className());
}

/// A one-line label narrower than its text or elided (its text cut with an
/// ellipsis, the whole in its tooltip), a wrapped label shorter than its
/// text, or a button narrower than its text.
inline QStringList clippedText(QWidget* w) {
  QStringList bad;
  auto* label = qobject_cast<QLabel*>(w);
  if (label && !label->text().isEmpty()) {
    // Rich text is measured as the words it shows.
    QString shown = label->text();
    if (label->textFormat() == Qt::RichText || (label->textFormat() == Qt::AutoText && Qt::mightBeRichText(shown))) {
      QTextDocument doc;
      doc.setHtml(shown);
      shown = doc.toPlainText();
    }
    if (label->wordWrap() && label->height() < label->heightForWidth(label->width()))
      bad << QStringLiteral("%1: %2 px tall, its text takes %3")
                 .arg(widgetName(w)).arg(label->height()).arg(label->heightForWidth(label->width()));
    if (shown.endsWith(QChar(0x2026)) && label->toolTip() != label->text())
      bad << QStringLiteral("%1: elided (whole: '%2')").arg(widgetName(w), label->toolTip());
    if (!label->wordWrap() && label->fontMetrics().horizontalAdvance(shown) > label->contentsRect().width())
      bad << QStringLiteral("%1: %2 px wide, its text takes %3")
                 .arg(widgetName(w)).arg(label->contentsRect().width())
                 .arg(label->fontMetrics().horizontalAdvance(shown));
  }
  auto* button = qobject_cast<QPushButton*>(w);
  if (button && button->fontMetrics().horizontalAdvance(button->text()) + 8 > button->width())
    bad << QStringLiteral("%1: %2 px wide, its text takes %3")
               .arg(widgetName(w)).arg(button->width()).arg(button->fontMetrics().horizontalAdvance(button->text()));
  return bad;
}

/// Of `panel` (a dock's contents): a widget outside the dock's view (below
/// the fold: the dock scrolls) and clippedText() of every label and button.
inline QStringList unreadable(QWidget* panel) {
  QWidget* view = panel;
  for (QWidget* w = panel->parentWidget(); w; w = w->parentWidget())
    if (auto* area = qobject_cast<QAbstractScrollArea*>(w)) {
      view = area->viewport();
      break;
    }
  QStringList bad;
  for (QWidget* w : panel->findChildren<QWidget*>()) {
    if (!w->isVisibleTo(view) || w->size().isEmpty()) continue;
    if (!qobject_cast<QLabel*>(w) && !qobject_cast<QPushButton*>(w) && !qobject_cast<QPlainTextEdit*>(w) &&
        !qobject_cast<QTreeWidget*>(w) && !qobject_cast<QTableWidget*>(w) && !qobject_cast<QSlider*>(w))
      continue;
    const QRect r(w->mapTo(view, QPoint(0, 0)), w->size());
    if (!view->rect().contains(r))
      bad << QStringLiteral("%1: at %2,%3 %4x%5, outside the dock's %6x%7")
                 .arg(widgetName(w)).arg(r.x()).arg(r.y()).arg(r.width()).arg(r.height())
                 .arg(view->width()).arg(view->height());
    bad << clippedText(w);
  }
  return bad;
}

/// Of the status bar: its message wider than the room Qt draws it in (left
/// of the first permanent field: past it the text is cut mid-letter), and
/// clippedText() of every permanent field.
inline QStringList unreadable(QStatusBar* bar) {
  QStringList bad;
  int right = bar->width() - 12;
  for (QWidget* w : bar->findChildren<QWidget*>(QString(), Qt::FindDirectChildrenOnly)) {
    if (!w->isVisible() || w->size().isEmpty() || !w->property("permanentField").toBool()) continue;
    right = std::min(right, w->x() - 2);
    bad << clippedText(w);
  }
  const QString message = bar->currentMessage();
  const int room = right - 6;
  if (bar->fontMetrics().horizontalAdvance(message) > room)
    bad << QStringLiteral("status message '%1...': %2 px wide, its text takes %3")
               .arg(message.left(40)).arg(room).arg(bar->fontMetrics().horizontalAdvance(message));
  return bad;
}

}  // namespace sp::test
