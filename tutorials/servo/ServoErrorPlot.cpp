#include "servo/ServoErrorPlot.h"

#include <visp3/core/vpColor.h>
#include <visp3/core/vpException.h>
#include <visp3/core/vpFont.h>
#include <visp3/core/vpImageDraw.h>
#include <visp3/core/vpImagePoint.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>

namespace hslam_servo
{
namespace
{
constexpr unsigned int kMarginLeft = 90, kMarginRight = 30, kMarginTop = 64, kMarginBottom = 50;
constexpr unsigned int kPanelGap = 60;
constexpr unsigned int kFontHeight = 16;
constexpr unsigned int kLineThickness = 2;
constexpr unsigned int kLegendLineLength = 30;
//! Smallest error shown on the log axes: below this the curves sit on the axis floor.
constexpr double kFloorMetres = 1e-5, kFloorDegrees = 1e-4;
constexpr double kTargetTimeTicks = 10.;

const vpColor kBackground(255, 255, 255);
const vpColor kGridColour(225, 225, 225);
const vpColor kTextColour(20, 20, 20);
const vpColor kServoColour(30, 80, 220);
const vpColor kSlamColour(220, 30, 30);
const vpColor kPhaseColour(120, 120, 120);

//! 1, 2 or 5 times a power of ten, at least \e raw.
double niceStep(double raw)
{
  const double power = std::pow(10., std::floor(std::log10(raw)));
  const double mantissa = raw / power;
  const double nice = mantissa <= 1. ? 1. : (mantissa <= 2. ? 2. : (mantissa <= 5. ? 5. : 10.));
  return nice * power;
}

//! One panel: a rectangle of the image, time on x, log10 of an error on y.
struct Panel {
  double top, bottom, left, right; //!< pixels
  double tMax;                     //!< seconds at the right edge
  double logLo, logHi;             //!< log10 of the errors at the bottom and top edges

  vpImagePoint at(double time, double value) const
  {
    const double y = (std::log10(value) - logLo) / (logHi - logLo);
    return vpImagePoint(bottom - y * (bottom - top), left + time / tMax * (right - left));
  }
};

void drawPanel(vpImage<vpRGBa> &I, const vpFont &font, const Panel &panel, const std::vector<ServoSample> &samples,
               const std::function<double(const ServoSample &)> &servo,
               const std::function<double(const ServoSample &)> &slam, double floor, const std::string &title)
{
  char text[64];
  // Decades and the time grid.
  for (double e = panel.logLo; e <= panel.logHi + 1e-9; e += 1.) {
    const double value = std::pow(10., e);
    const vpImagePoint a = panel.at(0., value), b = panel.at(panel.tMax, value);
    vpImageDraw::drawLine(I, a, b, kGridColour, 1);
    std::snprintf(text, sizeof(text), "1e%+d", static_cast<int>(std::lround(e)));
    font.drawText(I, text, vpImagePoint(a.get_i() - 0.5 * kFontHeight, 10.), kTextColour);
  }
  const double step = niceStep(panel.tMax / kTargetTimeTicks);
  for (double t = 0.; t <= panel.tMax + 1e-9; t += step) {
    vpImageDraw::drawLine(I, panel.at(t, std::pow(10., panel.logLo)), panel.at(t, std::pow(10., panel.logHi)),
                          kGridColour, 1);
    std::snprintf(text, sizeof(text), "%g", t);
    font.drawText(I, text, vpImagePoint(panel.bottom + 4., panel.at(t, 1.).get_j() - 8.), kTextColour);
  }
  font.drawText(I, title, vpImagePoint(panel.top - 1.5 * kFontHeight, panel.left), kTextColour);

  // End of the initialisation path.
  for (const ServoSample &s : samples) {
    if (s.servoing) {
      vpImageDraw::drawDottedLine(I, panel.at(s.time, std::pow(10., panel.logLo)),
                                  panel.at(s.time, std::pow(10., panel.logHi)), kPhaseColour, 2);
      font.drawText(I, "servo starts", vpImagePoint(panel.top + 4., panel.at(s.time, 1.).get_j() + 6.), kPhaseColour);
      break;
    }
  }

  auto curve = [&](const std::function<double(const ServoSample &)> &value, bool onlyEstimated, const vpColor &colour) {
    const ServoSample *previous = nullptr;
    for (const ServoSample &s : samples) {
      if (onlyEstimated && !s.hasEstimate) {
        previous = nullptr;
        continue;
      }
      if (previous) {
        vpImageDraw::drawLine(I, panel.at(previous->time, std::max(value(*previous), floor)),
                              panel.at(s.time, std::max(value(s), floor)), colour, kLineThickness);
      }
      previous = &s;
    }
  };
  curve(servo, false, kServoColour);
  curve(slam, true, kSlamColour);
}

//! log10 range covering the values (above \e floor) of both series, whole decades.
void logRange(const std::vector<ServoSample> &samples, const std::function<double(const ServoSample &)> &servo,
              const std::function<double(const ServoSample &)> &slam, double floor, double &lo, double &hi)
{
  double vMin = std::numeric_limits<double>::max(), vMax = floor;
  for (const ServoSample &s : samples) {
    for (double v : {servo(s), s.hasEstimate ? slam(s) : servo(s)}) {
      v = std::max(v, floor);
      vMin = std::min(vMin, v);
      vMax = std::max(vMax, v);
    }
  }
  lo = std::floor(std::log10(std::min(vMin, vMax)));
  hi = std::ceil(std::log10(vMax));
  if (hi <= lo) {
    hi = lo + 1.;
  }
}
} // namespace

void drawServoErrors(vpImage<vpRGBa> &I, const std::vector<ServoSample> &samples, const std::string &caption,
                     unsigned int width, unsigned int height)
{
  if (samples.size() < 2) {
    throw vpException(vpException::dimensionError, "servo plot: at least two samples are needed");
  }
  if (width < kMarginLeft + kMarginRight + 100 || height < kMarginTop + kMarginBottom + kPanelGap + 200) {
    throw vpException(vpException::dimensionError, "servo plot: image too small");
  }
  I.resize(height, width, vpRGBa(kBackground.R, kBackground.G, kBackground.B));
  // ViSP's bitmap font: the TrueType path of ViSP 3.5's vpFont corrupts memory (see TrajectoryPlot.cpp).
  const vpFont font(kFontHeight, vpFont::GENERIC_MONOSPACE);

  const double panelHeight = 0.5 * (height - kMarginTop - kMarginBottom - kPanelGap);
  const double tMax = std::max(samples.back().time, 1e-3);
  const std::function<double(const ServoSample &)> servoT = [](const ServoSample &s) { return s.servoErrorMetres; };
  const std::function<double(const ServoSample &)> slamT = [](const ServoSample &s) { return s.slamErrorMetres; };
  const std::function<double(const ServoSample &)> servoR = [](const ServoSample &s) { return s.servoErrorDegrees; };
  const std::function<double(const ServoSample &)> slamR = [](const ServoSample &s) { return s.slamErrorDegrees; };

  Panel translation = {static_cast<double>(kMarginTop),
                       kMarginTop + panelHeight,
                       static_cast<double>(kMarginLeft),
                       static_cast<double>(width - kMarginRight),
                       tMax,
                       0.,
                       1.};
  logRange(samples, servoT, slamT, kFloorMetres, translation.logLo, translation.logHi);
  drawPanel(I, font, translation, samples, servoT, slamT, kFloorMetres, "translation error (m)");

  Panel rotation = translation;
  rotation.top = translation.bottom + kPanelGap;
  rotation.bottom = rotation.top + panelHeight;
  logRange(samples, servoR, slamR, kFloorDegrees, rotation.logLo, rotation.logHi);
  drawPanel(I, font, rotation, samples, servoR, slamR, kFloorDegrees, "rotation error (deg)");

  font.drawText(I, "time (s)", vpImagePoint(height - 1.2 * kFontHeight, 0.5 * width - 30.), kTextColour);
  if (!caption.empty()) {
    font.drawText(I, caption, vpImagePoint(8., kMarginLeft), kTextColour);
  }
  // Legend, top right.
  double row = kMarginTop + 8.;
  const double left = width - kMarginRight - 260.;
  const struct {
    const char *label;
    vpColor colour;
  } legend[] = {{"servo error (to goal, true)", kServoColour}, {"SLAM error (vs simulator)", kSlamColour}};
  for (const auto &entry : legend) {
    vpImageDraw::drawLine(I, vpImagePoint(row + 0.5 * kFontHeight, left),
                          vpImagePoint(row + 0.5 * kFontHeight, left + kLegendLineLength), entry.colour,
                          kLineThickness + 1);
    font.drawText(I, entry.label, vpImagePoint(row, left + kLegendLineLength + 8.), kTextColour);
    row += 1.4 * kFontHeight;
  }
}
} // namespace hslam_servo
