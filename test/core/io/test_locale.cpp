// Locale independence: every scene loads to a bit-identical Model under de_DE.UTF-8 (',' as decimal separator),
// whether the locale comes from the environment, setlocale or std::locale::global; and the runner's files and
// messages are byte-identical under LC_ALL=de_DE.UTF-8 and LC_ALL=C. The locale must exist (scripts/common.sh
// generates it): these tests fail, never skip, without it.
#include <sys/wait.h>

#include <clocale>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <fstream>
#include <iterator>
#include <locale>
#include <regex>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <dirent.h>
#include <gtest/gtest.h>

#include "implicit_sim/core/io/pile_scene.h"
#include "implicit_sim/core/base/format.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "scenario_runner.h"
#include "test_files.h"

namespace implicit_sim {
namespace {

constexpr const char* kGerman = "de_DE.UTF-8";

// Restores the C locale, the global C++ locale and LC_ALL of the environment when it goes out of scope.
class LocaleGuard {
 public:
  LocaleGuard() : c_locale_(std::setlocale(LC_ALL, nullptr)), cpp_locale_() {
    const char* env = std::getenv("LC_ALL");
    had_env_ = env != nullptr;
    if (env) env_ = env;
  }
  ~LocaleGuard() {
    std::locale::global(cpp_locale_);
    std::setlocale(LC_ALL, c_locale_.c_str());
    if (had_env_) {
      ::setenv("LC_ALL", env_.c_str(), 1);
    } else {
      ::unsetenv("LC_ALL");
    }
  }

 private:
  std::string c_locale_;
  std::locale cpp_locale_;
  bool had_env_ = false;
  std::string env_;
};

std::string PrintfOneAndAHalf() {
  char buffer[16];
  std::snprintf(buffer, sizeof(buffer), "%.1f", 1.5);
  return buffer;
}

std::string StreamOneAndAHalf() {
  std::ostringstream out;
  out << 1.5;
  return out.str();
}

// Collects the names of every double (or other field) that differs between two models, bit for bit.
class ModelComparison {
 public:
  void Doubles(const std::string& what, const double* a, const double* b, size_t n) {
    if (std::memcmp(a, b, n * sizeof(double)) != 0) differences_.push_back(what);
  }
  template <typename EigenMatrix>
  void Matrix(const std::string& what, const EigenMatrix& a, const EigenMatrix& b) {
    Doubles(what, a.data(), b.data(), static_cast<size_t>(a.size()));
  }
  void Pose(const std::string& what, const implicit_sim::Pose& a, const implicit_sim::Pose& b) {
    Matrix(what, a.matrix(), b.matrix());
  }
  void Same(const std::string& what, bool equal) {
    if (!equal) differences_.push_back(what);
  }
  const std::vector<std::string>& differences() const { return differences_; }

 private:
  std::vector<std::string> differences_;
};

void CompareShapes(const std::string& at, const ConvexShape& a, const ConvexShape& b, ModelComparison* c) {
  c->Same(at + ".type", a.type == b.type);
  c->Matrix(at + ".size", a.size, b.size);
  c->Doubles(at + ".exponent", &a.exponent, &b.exponent, 1);
  c->Same(at + ".sides", a.sides == b.sides);
  c->Pose(at + ".X_BS", a.X_BS, b.X_BS);
  c->Same(at + ".inequalities.size", a.inequalities.size() == b.inequalities.size());
  for (size_t i = 0; i < std::min(a.inequalities.size(), b.inequalities.size()); ++i) {
    const Inequality& p = a.inequalities[i];
    const Inequality& q = b.inequalities[i];
    const std::string in = at + ".inequalities[" + std::to_string(i) + "]";
    c->Same(in + ".kind", p.kind == q.kind);
    c->Pose(in + ".X_SP", p.X_SP, q.X_SP);
    c->Matrix(in + ".normal", p.normal, q.normal);
    c->Doubles(in + ".offset", &p.offset, &q.offset, 1);
    c->Matrix(in + ".radii", p.radii, q.radii);
    c->Doubles(in + ".exponent", &p.exponent, &q.exponent, 1);
  }
}

// Every double of the Model compared with memcmp; other fields with ==.
::testing::AssertionResult BitIdentical(const Model& a, const Model& b) {
  ModelComparison c;
  c.Same("scene_name", a.scene_name == b.scene_name);
  c.Matrix("gravity_W", a.gravity_W, b.gravity_W);
  c.Same("bodies.size", a.bodies.size() == b.bodies.size());
  for (size_t i = 0; i < std::min(a.bodies.size(), b.bodies.size()); ++i) {
    const Body& p = a.bodies[i];
    const Body& q = b.bodies[i];
    const std::string at = "bodies[" + p.name + "]";
    c.Same(at + ".name", p.name == q.name);
    c.Same(at + ".is_fixed", p.is_fixed == q.is_fixed);
    c.Doubles(at + ".mass", &p.mass, &q.mass, 1);
    c.Matrix(at + ".I_B", p.I_B, q.I_B);
    c.Same(at + ".shapes.size", p.shapes.size() == q.shapes.size());
    for (size_t k = 0; k < std::min(p.shapes.size(), q.shapes.size()); ++k) {
      CompareShapes(at + ".shapes[" + std::to_string(k) + "]", p.shapes[k], q.shapes[k], &c);
    }
    c.Pose(at + ".X_BL", p.X_BL, q.X_BL);
    c.Pose(at + ".X_WB0", p.X_WB0, q.X_WB0);
    c.Matrix(at + ".v_WB0", p.v_WB0, q.v_WB0);
    c.Matrix(at + ".w_WB0", p.w_WB0, q.w_WB0);
    c.Matrix(at + ".f_applied_W", p.f_applied_W, q.f_applied_W);
    c.Matrix(at + ".tau_applied_W", p.tau_applied_W, q.tau_applied_W);
    c.Same(at + ".locked", p.locked == q.locked);
  }
  c.Same("pairs.size", a.pairs.size() == b.pairs.size());
  for (size_t i = 0; i < std::min(a.pairs.size(), b.pairs.size()); ++i) {
    const ContactPair& p = a.pairs[i];
    const ContactPair& q = b.pairs[i];
    const std::string at = "pairs[" + std::to_string(i) + "]";
    c.Same(at + ".bodies", p.body1 == q.body1 && p.body2 == q.body2);
    for (const auto& [name, x, y] : {std::make_tuple("mu", &p.friction.mu, &q.friction.mu),
                                     std::make_tuple("e_t", &p.friction.e_t, &q.friction.e_t),
                                     std::make_tuple("e_o", &p.friction.e_o, &q.friction.e_o),
                                     std::make_tuple("e_r", &p.friction.e_r, &q.friction.e_r)}) {
      c.Doubles(at + ".friction." + name, x, y, 1);
    }
  }
  c.Same("moving_bodies", a.moving_bodies == b.moving_bodies);
  c.Same("velocity_slot", a.velocity_slot == b.velocity_slot);
  c.Same("pairs_of_lower", a.pairs_of_lower == b.pairs_of_lower);
  if (c.differences().empty()) return ::testing::AssertionSuccess();
  std::string list;
  for (const std::string& d : c.differences()) list += " " + d;
  return ::testing::AssertionFailure() << "differs in:" << list;
}

// A scene with a fractional number in every attribute the loader or urdfdom reads: inertial origin and inertia,
// collision and joint origins with rpy, stock and implicit sizes, intersection parts, friction, body settings.
std::string EveryNumberScene() {
  const std::string inertial =
      "<inertial><origin xyz='0.0125 -0.25 0.5' rpy='0.1 -0.2 0.3'/><mass value='1.75'/>"
      "<inertia ixx='0.425' iyy='0.375' izz='0.55' ixy='0.0125' ixz='-0.025' iyz='0.0375'/></inertial>";
  return "<robot name='every_number'>"
         "<implicit_sim gravity='0.5 -0.25 -9.81'><friction mu='0.35' e_t='1.5' e_o='0.75' e_r='0.125'/>"
         "<friction link1='egg' link2='ground' mu='0.45' e_r='0.0625'/>"
         "<body link='egg' velocity='0.5 -1.25 0' angular_velocity='0 0.75 -2.5' force='0.1 0.2 0.3' "
         "torque='-0.1 0.05 0.025'/></implicit_sim>"
         "<link name='world'/>"
         "<link name='ground'><collision><origin xyz='0 0 -0.5' rpy='0.01 0.02 0'/><geometry>"
         "<box size='1.5 2.5 0.05'/></geometry><implicit type='halfspace'/></collision></link>"
         "<joint name='g' type='fixed'><parent link='world'/><child link='ground'/><origin xyz='0.25 0 0'/></joint>"
         "<link name='egg'>" + inertial + "<collision><origin xyz='0.1 0.2 0.3' rpy='0.4 0.5 0.6'/><geometry>"
         "<sphere radius='0.35'/></geometry><implicit type='superellipsoid' semi_axes='0.15 0.25 0.35' "
         "exponent='2.5'/></collision></link>"
         "<joint name='e' type='floating'><parent link='world'/><child link='egg'/>"
         "<origin xyz='0.5 -0.75 1.25' rpy='0.7 -0.8 0.9'/></joint>"
         "<link name='puck'><collision><origin rpy='1.5707963267948966 0 0'/><geometry><cylinder radius='0.25' "
         "length='0.125'/></geometry><implicit type='prism' sides='7' radius='0.25' length='0.125' mass='0.75'/>"
         "</collision></link>"
         "<joint name='p' type='floating'><parent link='world'/><child link='puck'/><origin xyz='1.5 0 0.5'/></joint>"
         "<link name='lens'><collision><geometry><box size='0.3 0.2 0.1'/></geometry><implicit type='intersection'>"
         "<sphere radius='0.45' xyz='0 0 -0.35'/><ellipsoid semi_axes='0.5 0.25 0.75' rpy='0.1 0 0'/>"
         "<superellipsoid semi_axes='0.5 0.5 0.5' exponent='3.5'/><cylinder radius='0.375' xyz='0.0625 0 0'/>"
         "<halfspace normal='0.25 0.5 1.5' offset='0.125'/></implicit></collision></link>"
         "<joint name='l' type='fixed'><parent link='world'/><child link='lens'/><origin xyz='-1.5 0 0.25'/></joint>"
         "<link name='brick'><collision><geometry><box size='0.3 0.2 0.1'/></geometry></collision>"
         "<inertial><mass value='0.5'/><inertia ixx='0.0025' iyy='0.0041' izz='0.0054' ixy='0' ixz='0' iyz='0'/>"
         "</inertial></link>"
         "<joint name='k' type='floating'><parent link='world'/><child link='brick'/><origin xyz='0 1.5 0.05'/></joint>"
         "</robot>";
}

struct NamedScene {
  std::string name, xml;
};

// Every scene of scenes/, the S1 pile generator's scenes and a scene with a fractional number everywhere.
std::vector<NamedScene> ScenesToCompare() {
  std::vector<NamedScene> scenes;
  const std::string dir = std::string(IMPLICIT_SIM_SOURCE_DIR) + "/scenes";
  if (DIR* d = ::opendir(dir.c_str())) {
    while (const dirent* entry = ::readdir(d)) {
      const std::string name = entry->d_name;
      if (name.size() <= 5 || name.substr(name.size() - 5) != ".urdf") continue;
      std::ifstream in(dir + "/" + name);
      scenes.push_back({name, std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>())});
    }
    ::closedir(d);
  }
  scenes.push_back({"pile_spheres", MakePileUrdf(30, PileShape::kSphere)});
  scenes.push_back({"pile_ellipsoids", MakePileUrdf(30, PileShape::kEllipsoid)});
  scenes.push_back({"every_number", EveryNumberScene()});
  return scenes;
}

std::vector<Model> LoadAll(const std::vector<NamedScene>& scenes) {
  std::vector<Model> models;
  for (const NamedScene& s : scenes) models.push_back(LoadSceneFromString(s.xml, s.name));
  return models;
}

// Loads every scene under the C locale, switches locales with `switch_locale`, loads again and compares.
void ExpectIdenticalModelsAfter(const std::function<void()>& switch_locale) {
  const std::vector<NamedScene> scenes = ScenesToCompare();
  ASSERT_GE(scenes.size(), 12u);  // 9 shipped scenes and 3 generated
  const std::vector<Model> reference = LoadAll(scenes);
  LocaleGuard guard;
  switch_locale();
  if (::testing::Test::HasFatalFailure()) return;
  EXPECT_EQ(FormatNumber(1.5), "1.5");
  const std::vector<Model> german = LoadAll(scenes);
  for (size_t i = 0; i < scenes.size(); ++i) EXPECT_TRUE(BitIdentical(reference[i], german[i])) << scenes[i].name;
}

// The comparison itself: one bit of one inertia entry, or one friction value, is a difference.
TEST(Locale, ComparisonFindsASingleBitDifference) {
  const Model a = LoadSceneFromString(EveryNumberScene());
  Model b = a;
  EXPECT_TRUE(BitIdentical(a, b));
  b.bodies[1].I_B(0, 1) = std::nextafter(b.bodies[1].I_B(0, 1), 1.0);
  const ::testing::AssertionResult differs = BitIdentical(a, b);
  EXPECT_FALSE(differs);
  EXPECT_NE(std::string(differs.message()).find("bodies[egg].I_B"), std::string::npos) << differs.message();
  b = a;
  b.pairs.back().friction.e_r = std::nextafter(b.pairs.back().friction.e_r, 0.0);
  EXPECT_FALSE(BitIdentical(a, b));
}

TEST(Locale, ModelsAreBitIdenticalWithLcAllFromTheEnvironment) {
  ExpectIdenticalModelsAfter([] {
    ::setenv("LC_ALL", kGerman, 1);
    ASSERT_NE(std::setlocale(LC_ALL, ""), nullptr) << "LC_ALL=" << kGerman << " cannot be set: generate the locale";
    ASSERT_EQ(PrintfOneAndAHalf(), "1,5");
  });
}

TEST(Locale, ModelsAreBitIdenticalAfterSetlocale) {
  ExpectIdenticalModelsAfter([] {
    ASSERT_NE(std::setlocale(LC_ALL, kGerman), nullptr) << kGerman << " cannot be set: generate the locale";
    ASSERT_EQ(PrintfOneAndAHalf(), "1,5");
  });
}

TEST(Locale, ModelsAreBitIdenticalAfterStdLocaleGlobal) {
  ExpectIdenticalModelsAfter([] {
    try {
      std::locale::global(std::locale(kGerman));  // a named locale: also sets the C locale
    } catch (const std::runtime_error& e) {
      FAIL() << kGerman << " cannot be set: " << e.what();
    }
    ASSERT_EQ(StreamOneAndAHalf(), "1,5");
    ASSERT_EQ(PrintfOneAndAHalf(), "1,5");
  });
}

TEST(Locale, ModelsAreBitIdenticalWithOnlyTheCppLocaleChanged) {
  ExpectIdenticalModelsAfter([] {
    try {  // an unnamed locale: the C locale stays "C", every new stream gets ',' as decimal point
      std::locale::global(std::locale(std::locale::classic(), new std::numpunct_byname<char>(kGerman)));
    } catch (const std::runtime_error& e) {
      FAIL() << kGerman << " cannot be set: " << e.what();
    }
    ASSERT_EQ(StreamOneAndAHalf(), "1,5");
  });
}

// --- the runner under LC_ALL=de_DE.UTF-8 and LC_ALL=C ---

using test_files::ReadText;

int RunUnderLocale(const std::string& locale, const std::string& args, const std::string& log_prefix) {
  const std::string command = "env LC_ALL=" + locale + " " + IMPLICIT_SIM_RUNNER + " " + args + " > '" + log_prefix +
                              ".stdout' 2> '" + log_prefix + ".stderr'";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// summary.json without its wall-time lines (wall_s, us_per_step), which differ from run to run.
std::string SummaryWithoutWallTime(const std::string& path) {
  std::istringstream in(ReadText(path));
  std::string line, kept;
  while (std::getline(in, line)) {
    if (line.find("\"wall_s\"") == std::string::npos && line.find("\"us_per_step\"") == std::string::npos) {
      kept += line + "\n";
    }
  }
  return kept;
}

// The runner's stdout line with the wall-time figure and the output directory replaced.
std::string StdoutWithoutWallTime(const std::string& text, const std::string& out_dir) {
  std::string line = std::regex_replace(text, std::regex("[-+.0-9e]+ us/step"), "X us/step");
  for (size_t at = line.find(out_dir); at != std::string::npos; at = line.find(out_dir)) {
    line.replace(at, out_dir.size(), "OUT");
  }
  return line;
}

// Six spheres resting on the ground: 21 candidate pairs, so the runner writes contacts.csv (broad phase).
std::string WriteRestingSpheresScene(const std::string& dir) {
  std::string xml =
      "<robot name='resting'><implicit_sim><friction mu='0.3' e_r='0.05'/></implicit_sim><link name='world'/>"
      "<link name='ground'><collision><geometry><box size='1 1 0.01'/></geometry><implicit type='halfspace'/>"
      "</collision></link><joint name='g' type='fixed'><parent link='world'/><child link='ground'/></joint>";
  for (int i = 0; i < 6; ++i) {
    const std::string name = "s" + std::to_string(i);
    xml += "<link name='" + name + "'><collision><geometry><sphere radius='0.1'/></geometry>"
           "<implicit type='sphere' radius='0.1' mass='0.3'/></collision></link><joint name='j" + name +
           "' type='floating'><parent link='world'/><child link='" + name + "'/><origin xyz='" +
           std::to_string(i) + ".25 0 0.1'/></joint>";
  }
  const std::string path = dir + "/resting_spheres.urdf";
  std::ofstream(path) << xml + "</robot>\n";
  return path;
}

TEST(Locale, TheGermanLocaleExistsForSubprocesses) {
  const std::string command = std::string("env LC_ALL=") + kGerman + " /usr/bin/printf '%.1f' 1.5 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  char buffer[256] = {0};
  const size_t n = std::fread(buffer, 1, sizeof(buffer) - 1, pipe);
  ::pclose(pipe);
  EXPECT_EQ(std::string(buffer, n), "1,5") << kGerman << " is missing: scripts/common.sh install_packages makes it";
}

TEST(Locale, RunnerOutputsAreByteIdenticalUnderGermanAndCLocales) {
  const std::string dir = ::testing::TempDir() + "implicit_sim_locale";
  std::system(("rm -rf '" + dir + "' && mkdir -p '" + dir + "'").c_str());
  const std::vector<std::pair<std::string, std::string>> runs = {
      {"p3", "--scene " + testing_support::ScenePath("p3_sphere_on_two_spheres.urdf") + " --duration 0.2 --dt 0.01"},
      {"resting", "--scene " + WriteRestingSpheresScene(dir) + " --duration 0.05 --dt 0.01"}};
  for (const auto& [name, args] : runs) {
    const std::string c_dir = dir + "/" + name + "_C", de_dir = dir + "/" + name + "_de";
    ASSERT_EQ(RunUnderLocale("C", args + " --out " + c_dir, c_dir), 0) << ReadText(c_dir + ".stderr");
    ASSERT_EQ(RunUnderLocale(kGerman, args + " --out " + de_dir, de_dir), 0) << ReadText(de_dir + ".stderr");
    for (const char* file : {"/trajectory.csv", "/contacts.csv"}) {
      EXPECT_EQ(ReadText(c_dir + file), ReadText(de_dir + file)) << name << file;
    }
    EXPECT_NE(ReadText(c_dir + "/trajectory.csv").find('.'), std::string::npos);
    EXPECT_EQ(SummaryWithoutWallTime(c_dir + "/summary.json"), SummaryWithoutWallTime(de_dir + "/summary.json"));
    EXPECT_EQ(StdoutWithoutWallTime(ReadText(c_dir + ".stdout"), c_dir),
              StdoutWithoutWallTime(ReadText(de_dir + ".stdout"), de_dir));
    EXPECT_EQ(ReadText(c_dir + ".stderr"), ReadText(de_dir + ".stderr"));
  }
  EXPECT_NE(ReadText(dir + "/resting_C/contacts.csv").find("s0-ground"), std::string::npos);
  // Refusals: messages with numbers in them.
  const std::string malformed = std::string(IMPLICIT_SIM_SOURCE_DIR) + "/test/data/malformed/";
  const std::string p2 = testing_support::ScenePath("p2_sphere_spinning.urdf");
  const std::vector<std::pair<std::string, std::string>> refusals = {
      {"mu", "--scene " + malformed + "friction_mu_negative.urdf --duration 1 --out " + dir + "/no1"},
      {"inertia", "--scene " + malformed + "inertia_indefinite_products.urdf --duration 1 --out " + dir + "/no2"},
      {"dt", "--scene " + p2 + " --duration 1 --dt 2.5 --out " + dir + "/no3"},
      {"tolerance", "--scene " + p2 + " --duration 1 --tolerance 1.5 --out " + dir + "/no4"}};
  for (const auto& [name, args] : refusals) {
    EXPECT_EQ(RunUnderLocale("C", args, dir + "/" + name + "_C"), 2);
    EXPECT_EQ(RunUnderLocale(kGerman, args, dir + "/" + name + "_de"), 2);
    const std::string message = ReadText(dir + "/" + name + "_C.stderr");
    EXPECT_EQ(message, ReadText(dir + "/" + name + "_de.stderr"));
    EXPECT_TRUE(std::regex_search(message, std::regex("[0-9]\\.[0-9]"))) << message;  // a number with a '.'
  }
  std::system(("rm -rf '" + dir + "'").c_str());
}

}  // namespace
}  // namespace implicit_sim
