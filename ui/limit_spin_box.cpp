#include "ui/limit_spin_box.h"

#include <QTimer>

#include <algorithm>
#include <cmath>

namespace sp {

namespace {
constexpr double kTypingRange = 1e6;  // what may be typed, whatever the limits
}

namespace {
// 0 for a value that shows as zero with `decimals` (dropping the sign of a
// negative zero too); else the value.
double withoutNegativeZero(double value, int decimals) {
  return std::round(value * std::pow(10.0, decimals)) == 0 ? 0.0 : value;
}
}  // namespace

QString formatFixed(double value, int decimals) {
  return QString::number(withoutNegativeZero(value, decimals), 'f', decimals);
}

LimitSpinBox::LimitSpinBox(QWidget* parent) : QDoubleSpinBox(parent) {
  QDoubleSpinBox::setRange(-kTypingRange, kTypingRange);
  setKeyboardTracking(false);  // one value per commit, not one per digit
  connect(this, &QDoubleSpinBox::valueChanged, this, &LimitSpinBox::onValueChanged);
}

void LimitSpinBox::setLimits(double lower, double upper) {
  lower_ = lower;
  upper_ = upper;
  updateGeometry();
}

QString LimitSpinBox::textFromValue(double value) const {
  return locale().toString(withoutNegativeZero(value, decimals()), 'f', decimals());
}

int LimitSpinBox::excessWidth() const {
  const QFontMetrics fm(font());
  const auto width = [&](double v) { return fm.horizontalAdvance(textFromValue(v) + suffix()); };
  const int typing = std::max(width(minimum()), width(maximum()));
  const int limits = std::max(width(lower_), width(upper_));
  return std::max(0, typing - limits);
}

QSize LimitSpinBox::sizeHint() const {
  QSize hint = QDoubleSpinBox::sizeHint();
  hint.rwidth() -= excessWidth();
  return hint;
}

QSize LimitSpinBox::minimumSizeHint() const {
  QSize hint = QDoubleSpinBox::minimumSizeHint();
  hint.rwidth() -= excessWidth();
  return hint;
}

void LimitSpinBox::stepBy(int steps) {
  // Steps stop at the limits rather than stepping into a refusal.
  const double next = std::clamp(value() + steps * singleStep(), lower_, upper_);
  setValue(next);
  selectAll();
}

void LimitSpinBox::onValueChanged(double v) {
  // The display rounds to decimals(); compare what is shown.
  const double tolerance = 0.5 * std::pow(10.0, -decimals());
  if (v < lower_ - tolerance || v > upper_ + tolerance) {
    const QString unit = suffix().trimmed();
    const QString why = tr("%1 %2 %3 is outside the limits [%4, %5] %3: not sent")
                            .arg(what_.isEmpty() ? tr("value") : what_, formatFixed(v, decimals()), unit,
                                 formatFixed(lower_, decimals()), formatFixed(upper_, decimals()));
    {
      const QSignalBlocker block(this);
      setValue(last_);
    }
    setStyleSheet(QStringLiteral("QDoubleSpinBox { background: #ffcdd2; }"));
    setToolTip(why);
    QTimer::singleShot(2000, this, [this] { setStyleSheet({}); });
    emit refused(why);
    return;
  }
  last_ = v;
  emit accepted(v);
}

}  // namespace sp
