// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Figures in messages: "1 chart", "175 charts", "0.771".

#include <cstdint>
#include <sstream>
#include <string>
#include <string_view>

namespace texfab {

/// "1 chart", "2 charts" (`plural` defaults to noun + "s").
inline std::string counted(int64_t n, std::string_view noun, std::string_view plural = {}) {
  std::string text = std::to_string(n);
  text += ' ';
  if (n == 1) text += noun;
  else if (!plural.empty()) text += plural;
  else text.append(noun).append("s");
  return text;
}

/// A number with 3 significant digits: "0.771", "1.25e+03".
inline std::string figure(double v) {
  std::ostringstream s;
  s.precision(3);
  s << v;
  return s.str();
}

} // namespace texfab
