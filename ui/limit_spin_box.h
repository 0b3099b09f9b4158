#pragma once
// A number box for a value with limits that refuses, visibly, a typed value
// beyond them instead of silently changing it: a plain QDoubleSpinBox with
// range [-30, 30] turns a typed "99" into "9" (its validator drops the
// second digit). Here any number may be typed; on commit a value outside
// the limits is refused (refused() says why, the box flashes red, the last
// good value comes back) and only a value within them is accepted().
// Zero never shows as "-0.0".
//
// Thread: GUI thread only.

#include <QDoubleSpinBox>

namespace sp {

class LimitSpinBox : public QDoubleSpinBox {
  Q_OBJECT

 public:
  explicit LimitSpinBox(QWidget* parent = nullptr);

  /// The accepted range; the box itself takes any number to be typed.
  void setLimits(double lower, double upper);
  double lower() const { return lower_; }
  double upper() const { return upper_; }
  /// What a refusal calls the value, e.g. "knee_fl target".
  void setWhat(const QString& what) { what_ = what; }

 signals:
  /// A value within the limits, typed, stepped or set.
  void accepted(double value);
  /// A typed value beyond the limits, with why: it was not applied.
  void refused(const QString& why);

 protected:
  QString textFromValue(double value) const override;
  /// As wide as the limits' values need, not the typing range's.
  QSize sizeHint() const override;
  QSize minimumSizeHint() const override;
  void stepBy(int steps) override;

 private:
  void onValueChanged(double value);
  /// How much narrower the limits' longest text is than the typing range's [px].
  int excessWidth() const;

  double lower_ = -1e9, upper_ = 1e9;
  double last_ = 0;
  QString what_;
};

/// `value` with `decimals` decimals, never "-0.0" (a value that rounds to
/// zero shows as zero, whatever its sign).
QString formatFixed(double value, int decimals);

}  // namespace sp
