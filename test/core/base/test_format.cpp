// FormatNumber: the shortest text that reads back to the same double, "nan"/"inf"/"-inf", and '.' as the decimal
// point under a German global C++ locale.
#include "implicit_sim/core/base/format.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <locale>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace implicit_sim {
namespace {

const std::vector<double> kValues = {0.0, 1.0, -2.5, 0.1, 1.0 / 3.0, 2.0 / 3.0, 1e-5, 123456789.125, 6.02214076e23,
                                     -1e-300, 5e-324, std::numeric_limits<double>::max(),
                                     std::numeric_limits<double>::min(), std::nextafter(1.0, 2.0), M_PI};

double ReadBack(const std::string& text) { return std::strtod(text.c_str(), nullptr); }

// `value` printed with `digits` significant digits (%.*g, C locale at the time of the test).
std::string WithDigits(double value, int digits) {
  char buffer[512];  // %g of any double fits
  std::snprintf(buffer, sizeof(buffer), "%.*g", digits, value);
  return buffer;
}

// The digits of the mantissa from its first to its last nonzero one ("0.0120" and "1.2e-02": 2).
int SignificantDigits(const std::string& text) {
  const std::string mantissa = text.substr(0, text.find('e'));
  std::string digits;
  for (char c : mantissa) {
    if (c >= '0' && c <= '9') digits += c;
  }
  const size_t first = digits.find_first_not_of('0');
  if (first == std::string::npos) return 0;
  return static_cast<int>(digits.find_last_not_of('0') - first + 1);
}

TEST(FormatNumber, RoundTripsEveryDouble) {
  for (double v : kValues) {
    const std::string text = FormatNumber(v);
    const double back = ReadBack(text);
    EXPECT_EQ(std::memcmp(&back, &v, sizeof(double)), 0) << text;
  }
}

TEST(FormatNumber, UsesTheShortestForm) {
  EXPECT_EQ(FormatNumber(0.1), "0.1");
  EXPECT_EQ(FormatNumber(1.5), "1.5");
  EXPECT_EQ(FormatNumber(-2.5), "-2.5");
  EXPECT_EQ(FormatNumber(0.0), "0");
  EXPECT_EQ(FormatNumber(100.0), "100");
  EXPECT_EQ(FormatNumber(1.0 / 3.0), "0.3333333333333333");
  for (double v : kValues) {  // one significant digit fewer does not read back to v
    const std::string text = FormatNumber(v);
    const int digits = SignificantDigits(text);
    EXPECT_LE(digits, 17) << text;
    if (digits > 1) {
      EXPECT_NE(ReadBack(WithDigits(v, digits - 1)), v) << text;
    }
  }
}

TEST(FormatNumber, PrintsNonFiniteValuesPlainly) {
  EXPECT_EQ(FormatNumber(std::numeric_limits<double>::quiet_NaN()), "nan");
  EXPECT_EQ(FormatNumber(-std::numeric_limits<double>::quiet_NaN()), "nan");
  EXPECT_EQ(FormatNumber(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(FormatNumber(-std::numeric_limits<double>::infinity()), "-inf");
}

// Sets the global C++ locale (and the C locale with it) for its lifetime.
class GlobalLocale {
 public:
  explicit GlobalLocale(const std::locale& locale) : previous_(std::locale::global(locale)) {}
  ~GlobalLocale() { std::locale::global(previous_); }

 private:
  std::locale previous_;
};

TEST(FormatNumber, UsesAPointUnderAGermanGlobalLocale) {
  std::locale german;
  try {
    german = std::locale("de_DE.UTF-8");
  } catch (const std::runtime_error&) {
    GTEST_SKIP() << "locale de_DE.UTF-8 is not installed";
  }
  const GlobalLocale guard(german);
  ASSERT_EQ(WithDigits(1.5, 2), "1,5");  // the C locale follows the global one: printf would write a comma
  EXPECT_EQ(FormatNumber(1.5), "1.5");
  EXPECT_EQ(FormatNumber(-1234.5), "-1234.5");
  EXPECT_EQ(FormatNumber(1.0 / 3.0), "0.3333333333333333");
  EXPECT_EQ(FormatNumber(std::numeric_limits<double>::quiet_NaN()), "nan");
}

}  // namespace
}  // namespace implicit_sim
