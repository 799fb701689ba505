// SPDX-License-Identifier: GPL-3.0-or-later
#include "print/color_difference.h"

#include <cmath>
#include <cstddef>

namespace texfab::print {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kD65[3] = {0.95047, 1.0, 1.08883};
constexpr double kD50[3] = {0.96422, 1.0, 0.82521};

double labF(double t) {
  constexpr double d = 6.0 / 29.0;
  return t > d * d * d ? std::cbrt(t) : t / (3 * d * d) + 4.0 / 29.0;
}
double labFDerivative(double t) {
  constexpr double d = 6.0 / 29.0;
  return t > d * d * d ? 1.0 / (3.0 * std::cbrt(t * t)) : 1.0 / (3 * d * d);
}
double labFInverse(double f) {
  constexpr double d = 6.0 / 29.0;
  return f > d ? f * f * f : 3 * d * d * (f - 4.0 / 29.0);
}
double degrees(double radians) { return radians * 180 / kPi; }
double radians(double degrees) { return degrees * kPi / 180; }

} // namespace

Lab labFromLinearSrgb(const std::array<double, 3>& c) {
  const double x = 0.4124564 * c[0] + 0.3575761 * c[1] + 0.1804375 * c[2];
  const double y = 0.2126729 * c[0] + 0.7151522 * c[1] + 0.0721750 * c[2];
  const double z = 0.0193339 * c[0] + 0.1191920 * c[1] + 0.9503041 * c[2];
  const double fx = labF(x / kD65[0]), fy = labF(y / kD65[1]), fz = labF(z / kD65[2]);
  return {116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz)};
}

Lab labD50FromLinearSrgb(const std::array<double, 3>& c) {
  const double x = 0.4124564 * c[0] + 0.3575761 * c[1] + 0.1804375 * c[2];
  const double y = 0.2126729 * c[0] + 0.7151522 * c[1] + 0.0721750 * c[2];
  const double z = 0.0193339 * c[0] + 0.1191920 * c[1] + 0.9503041 * c[2];
  // Bradford D65 -> D50.
  const double x50 = 1.0478112 * x + 0.0228866 * y - 0.0501270 * z;
  const double y50 = 0.0295424 * x + 0.9904844 * y - 0.0170491 * z;
  const double z50 = -0.0092345 * x + 0.0150436 * y + 0.7521316 * z;
  const double fx = labF(x50 / kD50[0]), fy = labF(y50 / kD50[1]), fz = labF(z50 / kD50[2]);
  return {116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz)};
}

std::array<double, 9> labJacobian(const std::array<double, 3>& c) {
  static constexpr double m[3][3] = {{0.4124564, 0.3575761, 0.1804375},
                                     {0.2126729, 0.7151522, 0.0721750},
                                     {0.0193339, 0.1191920, 0.9503041}};
  double d[3];  // d f(t) / d XYZ per axis
  for (int k = 0; k < 3; ++k) {
    const double t = (m[k][0] * c[0] + m[k][1] * c[1] + m[k][2] * c[2]) / kD65[k];
    d[k] = labFDerivative(t) / kD65[k];
  }
  std::array<double, 9> j{};
  for (int col = 0; col < 3; ++col) {
    j[size_t(col)] = 116 * d[1] * m[1][col];
    j[size_t(3 + col)] = 500 * (d[0] * m[0][col] - d[1] * m[1][col]);
    j[size_t(6 + col)] = 200 * (d[1] * m[1][col] - d[2] * m[2][col]);
  }
  return j;
}

std::array<double, 3> linearSrgbFromLabD50(const Lab& lab) {
  const double fy = (lab[0] + 16) / 116, fx = fy + lab[1] / 500, fz = fy - lab[2] / 200;
  const double x50 = kD50[0] * labFInverse(fx), y50 = kD50[1] * labFInverse(fy), z50 = kD50[2] * labFInverse(fz);
  // Bradford D50 -> D65.
  const double x = 0.9555766 * x50 - 0.0230393 * y50 + 0.0631636 * z50;
  const double y = -0.0282895 * x50 + 1.0099416 * y50 + 0.0210077 * z50;
  const double z = 0.0122982 * x50 - 0.0204830 * y50 + 1.3299098 * z50;
  return {3.2404542 * x - 1.5371385 * y - 0.4985314 * z, -0.9692660 * x + 1.8760108 * y + 0.0415560 * z,
          0.0556434 * x - 0.2040259 * y + 1.0572252 * z};
}

std::array<double, 9> deltaE2000Metric(const Lab& p) {
  const double c = std::hypot(p[1], p[2]);
  const double c7 = std::pow(c, 7), g = 0.5 * (1 - std::sqrt(c7 / (c7 + std::pow(25.0, 7))));
  const double a = (1 + g) * p[1], cp = std::hypot(a, p[2]);
  const double h = cp > 0 ? std::atan2(p[2], a) : 0.0, hDeg = degrees(h) < 0 ? degrees(h) + 360 : degrees(h);
  const double t = 1 - 0.17 * std::cos(radians(hDeg - 30)) + 0.24 * std::cos(radians(2 * hDeg)) +
                   0.32 * std::cos(radians(3 * hDeg + 6)) - 0.20 * std::cos(radians(4 * hDeg - 63));
  const double l50 = (p[0] - 50) * (p[0] - 50);
  const double sL = 1 + 0.015 * l50 / std::sqrt(20 + l50), sC = 1 + 0.045 * cp, sH = 1 + 0.015 * cp * t;
  // dC' = cos h da' + sin h db, dH' = -sin h da' + cos h db, da' = (1 + G) da.
  return {1 / sL, 0, 0, 0, std::cos(h) * (1 + g) / sC, std::sin(h) / sC, 0, -std::sin(h) * (1 + g) / sH, std::cos(h) / sH};
}

double deltaE2000(const Lab& p, const Lab& q) {
  const double c1 = std::hypot(p[1], p[2]), c2 = std::hypot(q[1], q[2]);
  const double cBar7 = std::pow((c1 + c2) / 2, 7), k7 = std::pow(25.0, 7);
  const double g = 0.5 * (1 - std::sqrt(cBar7 / (cBar7 + k7)));
  const double a1 = (1 + g) * p[1], a2 = (1 + g) * q[1];
  const double c1p = std::hypot(a1, p[2]), c2p = std::hypot(a2, q[2]);
  auto hue = [](double b, double a) {
    if (a == 0 && b == 0) return 0.0;
    const double h = degrees(std::atan2(b, a));
    return h < 0 ? h + 360 : h;
  };
  const double h1 = hue(p[2], a1), h2 = hue(q[2], a2);
  const double dL = q[0] - p[0], dC = c2p - c1p;
  double dh = 0;
  if (c1p * c2p != 0) {
    dh = h2 - h1;
    if (dh > 180) dh -= 360;
    else if (dh < -180) dh += 360;
  }
  const double dH = 2 * std::sqrt(c1p * c2p) * std::sin(radians(dh / 2));
  const double lBar = (p[0] + q[0]) / 2, cBarP = (c1p + c2p) / 2;
  double hBar = h1 + h2;
  if (c1p * c2p != 0) {
    if (std::abs(h1 - h2) <= 180) hBar = (h1 + h2) / 2;
    else hBar = h1 + h2 < 360 ? (h1 + h2 + 360) / 2 : (h1 + h2 - 360) / 2;
  }
  const double t = 1 - 0.17 * std::cos(radians(hBar - 30)) + 0.24 * std::cos(radians(2 * hBar)) +
                   0.32 * std::cos(radians(3 * hBar + 6)) - 0.20 * std::cos(radians(4 * hBar - 63));
  const double dTheta = 30 * std::exp(-std::pow((hBar - 275) / 25, 2));
  const double cBarP7 = std::pow(cBarP, 7);
  const double rC = 2 * std::sqrt(cBarP7 / (cBarP7 + k7));
  const double l50 = (lBar - 50) * (lBar - 50);
  const double sL = 1 + 0.015 * l50 / std::sqrt(20 + l50), sC = 1 + 0.045 * cBarP, sH = 1 + 0.015 * cBarP * t;
  const double rT = -std::sin(radians(2 * dTheta)) * rC;
  const double l = dL / sL, c = dC / sC, h = dH / sH;
  return std::sqrt(l * l + c * c + h * h + rT * c * h);
}

} // namespace texfab::print
