// implicit_sim_make_pile --n N --shape sphere|ellipsoid|bracket|tee [--seed S] [--orientation aligned|random]
// [--e-r M] [--e-roll M] --out FILE: writes the S1 pile scene (torsional lever e_r, in m, default 0.01, 0 for none;
// rolling resistance M, in m, on its friction when M > 0).
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <string>

#include "implicit_sim/core/io/pile_scene.h"

int main(int argc, char** argv) {
  const char* usage =
      "usage: implicit_sim_make_pile --n N --shape sphere|ellipsoid|bracket|tee [--seed S] "
      "[--orientation aligned|random] [--e-r M] [--e-roll M] --out FILE";
  std::map<std::string, std::string> values;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if ((flag != "--n" && flag != "--shape" && flag != "--seed" && flag != "--orientation" && flag != "--e-roll" &&
         flag != "--e-r" && flag != "--out") ||
        i + 1 >= argc) {
      std::cerr << "implicit_sim_make_pile: bad argument '" << flag << "' (" << usage << ")\n";
      return 2;
    }
    values[flag] = argv[++i];
  }
  if (!values.count("--n") || !values.count("--shape") || !values.count("--out")) {
    std::cerr << "implicit_sim_make_pile: " << usage << "\n";
    return 2;
  }
  const std::string& shape = values["--shape"];
  char* end = nullptr;
  const long n = std::strtol(values["--n"].c_str(), &end, 10);
  const bool n_ok = *end == '\0' && n >= 1;
  const long seed = values.count("--seed") ? std::strtol(values["--seed"].c_str(), &end, 10) : 42;
  implicit_sim::PileShape pile_shape;
  if (!n_ok || !implicit_sim::ParsePileShape(shape, &pile_shape) || *end != '\0' || seed < 0 ||
      n > implicit_sim::MaxPileSize(pile_shape)) {
    std::cerr << "implicit_sim_make_pile: --n must be in [1, 4000] (sphere, ellipsoid) or [1, 2000] (bracket, tee), "
                 "--shape sphere, ellipsoid, bracket or tee, --seed >= 0\n";
    return 2;
  }
  const std::string orientation = values.count("--orientation") ? values["--orientation"] : "aligned";
  if (orientation != "aligned" && orientation != "random") {
    std::cerr << "implicit_sim_make_pile: --orientation must be aligned or random, got '" << orientation << "'\n";
    return 2;
  }
  double e_roll = 0.0;
  if (values.count("--e-roll")) {
    e_roll = std::strtod(values["--e-roll"].c_str(), &end);
    if (values["--e-roll"].empty() || *end != '\0' || !(e_roll >= 0.0 && e_roll <= 1000.0)) {
      std::cerr << "implicit_sim_make_pile: --e-roll must be a number in [0, 1000] m, got '" << values["--e-roll"]
                << "'\n";
      return 2;
    }
  }
  double e_r = implicit_sim::kPileTorsionLever;
  if (values.count("--e-r")) {
    e_r = std::strtod(values["--e-r"].c_str(), &end);
    if (values["--e-r"].empty() || *end != '\0' || !(e_r >= 0.0 && e_r <= 1000.0)) {
      std::cerr << "implicit_sim_make_pile: --e-r must be a number in [0, 1000] m, got '" << values["--e-r"] << "'\n";
      return 2;
    }
  }
  // The generator's std::mt19937 takes the seed modulo 2^32.
  const std::string urdf = implicit_sim::MakePileUrdf(
      static_cast<int>(n), pile_shape, static_cast<unsigned>(seed), true,
      orientation == "random" ? implicit_sim::PileOrientation::kRandom : implicit_sim::PileOrientation::kAligned,
      e_roll, e_r);
  std::ofstream out(values["--out"]);
  out << urdf;
  if (!out) {
    std::cerr << "implicit_sim_make_pile: cannot write '" << values["--out"] << "'\n";
    return 1;
  }
  return 0;
}
