// implicit_sim_mujoco_bench: the benchmark cases of implicit_sim_bench run in MuJoCo (Debian's libmujoco-dev 2.2.2),
// one JSON line per run with implicit_sim_bench's field names where they apply, "engine": "mujoco", and the same
// accuracy fields (bench/scenario_metrics.h). The scene is our own scene file (or our S1 pile generator) loaded by our
// loader and written as MJCF (mjcf_scene.h), so both engines run the same bodies. Only the time inside mj_step counts.
//   implicit_sim_mujoco_bench                                   every case
//   implicit_sim_mujoco_bench --scenario P1 --variant p1_ngon100
//   implicit_sim_mujoco_bench --scenario S1 --shape ellipsoid --n 100 [--e-r M] [--duration 2] [--dt 0.005]
//                             [--solver CG]
// Flags and fields: bench/README.md#side-by-side-with-mujoco. Bad arguments: exit 2 and one line on stderr.
#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "../scenario_metrics.h"
#include "implicit_sim/core/base/format.h"
#include "implicit_sim/core/io/pile_scene.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "mjcf_scene.h"

namespace {
using namespace implicit_sim;

struct Case {
  std::string scenario;  // P1, P2, P3, S1
  std::string variant;   // P: the scene file's name; S1: <shape>_n<N>, then _er<M> (implicit_sim_bench's)
  double h = 0.01;       // s
  double duration = 1.0; // s
  std::string scene_file;
  PileShape shape = PileShape::kSphere;
  int n = 0;
  unsigned seed = 42;
  double e_r = kPileTorsionLever;  // S1: the torsional lever (m; 0: none, condim 3)
};

// implicit_sim_bench's cases (AllCases there), in the same order.
std::vector<Case> AllCases() {
  std::vector<Case> cases = {
      {"P1", "p1_disc_rolling", 0.01, 5.0, "p1_disc_rolling.urdf"},
      {"P1", "p1_ngon100", 0.01, 5.0, "p1_ngon100.urdf"},
      {"P2", "p2_sphere_spinning", 0.07, 1.4, "p2_sphere_spinning.urdf"},
      {"P2", "p2_sphere_spinning", 0.01, 1.4, "p2_sphere_spinning.urdf"},
      {"P3", "p3_sphere_on_two_spheres", 0.01, 5.0, "p3_sphere_on_two_spheres.urdf"},
  };
  for (PileShape shape : {PileShape::kSphere, PileShape::kEllipsoid}) {
    for (int n : {10, 100, 1000}) {
      Case c{"S1", std::string(shape == PileShape::kSphere ? "sphere" : "ellipsoid") + "_n" + std::to_string(n),
             0.005, 2.0, "", shape, n, 42};
      cases.push_back(c);
    }
  }
  return cases;
}

// MuJoCo's messages go to stderr (stdout is the JSONL); an error ends the program.
void WarningToStderr(const char* message) { std::cerr << "mujoco: " << message << "\n"; }
void ErrorToStderr(const char* message) {
  std::cerr << "implicit_sim_mujoco_bench: mujoco error: " << message << "\n";
  std::exit(1);
}

// Compiles an MJCF string through MuJoCo's virtual file system.
mjModel* CompileMjcf(const std::string& xml) {
  auto vfs = std::make_unique<mjVFS>();  // about 2 MB: not on the stack
  mj_defaultVFS(vfs.get());
  const char* file = "scene.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), file, static_cast<int>(xml.size())) != 0) throw std::runtime_error("VFS full");
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), file)], xml.data(), xml.size());
  char error[1000] = "";
  mjModel* m = mj_loadXML(file, vfs.get(), error, sizeof(error));
  mj_deleteVFS(vfs.get());
  if (!m) throw std::runtime_error(std::string("MuJoCo cannot compile the scene: ") + error);
  return m;
}

// One case in MuJoCo: our model, its MJCF twin, and the map from MuJoCo geoms to our bodies.
struct MujocoScene {
  Model model;
  mjModel* m = nullptr;
  mjData* d = nullptr;
  std::vector<int> body_of_geom;  // MuJoCo geom id -> our body index
  int first_moving = -1;          // MuJoCo body id of our first moving body
  ~MujocoScene() {
    if (d) mj_deleteData(d);
    if (m) mj_deleteModel(m);
  }
};

// Sets qvel from our initial velocities (a free joint's angular velocity is in the body frame) and xfrc_applied from
// our constant applied forces.
void SetInitialState(MujocoScene* s) {
  for (int body : s->model.moving_bodies) {
    const Body& b = s->model.bodies[body];
    const int id = mj_name2id(s->m, mjOBJ_BODY, b.name.c_str());
    const int dof = s->m->jnt_dofadr[s->m->body_jntadr[id]];
    mjtNum* qvel = s->d->qvel + dof;
    if (s->m->jnt_type[s->m->body_jntadr[id]] == mjJNT_FREE) {
      const Vec3 w_B = b.X_WB0.linear().transpose() * b.w_WB0;
      for (int i = 0; i < 3; ++i) qvel[i] = b.v_WB0[i], qvel[3 + i] = w_B[i];
    } else {  // slide x, slide z, hinge y (mjcf_scene.h)
      qvel[0] = b.v_WB0.x(), qvel[1] = b.v_WB0.z(), qvel[2] = b.w_WB0.y();
    }
    for (int i = 0; i < 3; ++i) {
      s->d->xfrc_applied[6 * id + i] = b.f_applied_W[i];
      s->d->xfrc_applied[6 * id + 3 + i] = b.tau_applied_W[i];
    }
  }
  mj_forward(s->m, s->d);
}

std::unique_ptr<MujocoScene> LoadScene(const Case& c, const std::string& scenes_dir, const std::string& solver) {
  auto s = std::make_unique<MujocoScene>();
  s->model = c.scenario == "S1"
                 ? LoadSceneFromString(MakePileUrdf(c.n, c.shape, c.seed, true, PileOrientation::kAligned, 0.0, c.e_r),
                                       "s1_" + c.variant)
                 : LoadSceneFromFile(scenes_dir + "/" + c.scene_file);
  MjcfOptions options;
  options.h = c.h;
  options.solver = solver.empty() ? (c.scenario == "S1" ? "CG" : "Newton") : solver;
  if (c.scenario == "S1") {  // room for every contact of the pile (4 constraint rows each at condim 4)
    options.max_contacts = 8 * c.n + 50;
    // 2.2.2: mjData must stay < 2 GiB, and its stack (a heuristic growing with njmax x nv) must fit: at N = 1000
    // (nv = 6000) mj_makeData fails with 10 000 rows and works with 8000 (measured 2026-12-02).
    options.max_constraint_rows = std::min(4 * options.max_contacts, c.n <= 500 ? 10000 : 8000);
  }
  s->m = CompileMjcf(MjcfFromModel(s->model, options));
  s->d = mj_makeData(s->m);
  s->body_of_geom.assign(s->m->ngeom, -1);
  for (int g = 0; g < s->m->ngeom; ++g) s->body_of_geom[g] = s->model.FindBody(mj_id2name(s->m, mjOBJ_GEOM, g));
  s->first_moving = mj_name2id(s->m, mjOBJ_BODY, s->model.bodies[s->model.moving_bodies.front()].name.c_str());
  SetInitialState(s.get());
  return s;
}

// J: qvel' M qvel / 2, with the mass matrix of the last forward pass (mj_step's: the state at the step's start).
double KineticEnergy(const mjModel* m, const mjData* d, const mjtNum* qvel) {
  std::vector<mjtNum> Mv(m->nv);
  mj_mulM(m, d, Mv.data(), qvel);
  return 0.5 * mju_dot(Mv.data(), qvel, m->nv);
}

double MaxPenetration(const mjData* d) {  // m: the deepest contact of the last collision detection
  double deepest = 0.0;
  for (int i = 0; i < d->ncon; ++i) deepest = std::max(deepest, -d->contact[i].dist);
  return deepest;
}

// The paper scenes' sample (scenario_metrics.h) of the state at time t that the last forward pass saw, with its
// velocities qvel: the first moving body; P3's contacts by pair name.
StepSample SampleOf(const MujocoScene& s, double t, const mjtNum* qvel) {
  StepSample sample;
  sample.t = t;
  sample.kinetic_energy = KineticEnergy(s.m, s.d, qvel);
  mjtNum velocity[6];  // angular, then linear velocity at the body origin (the centre of mass), world frame
  mj_objectVelocity(s.m, s.d, mjOBJ_BODY, s.first_moving, velocity, 0);
  for (int i = 0; i < 3; ++i) sample.w_W[i] = velocity[i], sample.v_W[i] = velocity[3 + i];
  for (int i = 0; i < s.d->ncon; ++i) {
    const mjContact& contact = s.d->contact[i];
    const int pair = s.model.PairIndex(s.body_of_geom[contact.geom1], s.body_of_geom[contact.geom2]);
    const std::string name = pair >= 0 ? s.model.PairName(pair) : "";
    const int c = name == "ball-sphere_a" ? 0 : name == "ball-sphere_b" ? 1 : -1;
    if (c < 0) continue;
    mjtNum force[6];  // normal, tangential, torsional, in the contact frame (N, N m)
    mj_contactForce(s.m, s.d, i, force);
    sample.closed[c] = sample.closed[c] || force[0] > 1e-9;
    const mjtNum* x = s.d->xpos + 3 * s.first_moving;
    const Vec3 r(contact.pos[0] - x[0], contact.pos[1] - x[1], contact.pos[2] - x[2]);  // m
    const Vec3 v = Vec3(velocity[3], velocity[4], velocity[5]) + Vec3(velocity[0], velocity[1], velocity[2]).cross(r);
    const Vec3 n(contact.frame[0], contact.frame[1], contact.frame[2]);
    sample.slip_speed[c] = (v - v.dot(n) * n).norm();  // the other sphere is fixed
  }
  return sample;
}

std::string Field(const std::string& key, const std::string& value) { return "\"" + key + "\": " + value; }
std::string Quoted(const std::string& text) { return "\"" + text + "\""; }

// Runs one case and prints its JSON line. mj_step's forward pass evaluates the state at the step's start, i.e. the
// previous step's end: the figures of step end k are read after step k + 1 (and after a final mj_forward for the
// last), because an extra mj_forward between steps would change MuJoCo's warm start and so its trajectory.
void Run(const Case& c, const std::string& scenes_dir, double max_wall_s, const std::string& solver) {
  const std::unique_ptr<MujocoScene> s = LoadScene(c, scenes_dir, solver);
  mjModel* m = s->m;
  mjData* d = s->d;
  const double kinetic_energy_initial = KineticEnergy(m, d, d->qvel);
  ScenarioMetrics metrics(c.scenario, kinetic_energy_initial);
  const long steps = std::lround(c.duration / c.h);
  long done = 0;
  double wall_s = 0.0, max_penetration = 0.0, iterations = 0.0;  // s, m, solver iterations
  int max_contacts = 0;
  std::vector<mjtNum> qvel_before(m->nv);
  const auto observe_last_forward = [&](double t) {  // the state the last forward pass saw, at time t
    max_penetration = std::max(max_penetration, MaxPenetration(d));
    max_contacts = std::max(max_contacts, d->ncon);
    if (metrics.NeedsSamples() && t > 0.0) metrics.Observe(SampleOf(*s, t, qvel_before.data()));
  };
  while (done < steps && wall_s <= max_wall_s) {
    mju_copy(qvel_before.data(), d->qvel, m->nv);
    const auto start = std::chrono::steady_clock::now();
    mj_step(m, d);
    wall_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    observe_last_forward(done * c.h);
    ++done;
    iterations += d->solver_iter;
  }
  mju_copy(qvel_before.data(), d->qvel, m->nv);
  mj_forward(m, d);  // the last step end
  observe_last_forward(done * c.h);
  const int overflows = d->warning[mjWARN_CONTACTFULL].number + d->warning[mjWARN_CNSTRFULL].number;
  std::vector<std::string> fields = {
      Field("scenario", Quoted(c.scenario)),
      Field("variant", Quoted(c.variant)),
      Field("bodies", std::to_string(s->model.num_moving())),
      Field("h", FormatNumber(c.h)),
      Field("steps", std::to_string(done)),
      Field("completed", done == steps ? "true" : "false"),
      Field("simulated_s", FormatNumber(done * c.h)),
      Field("wall_s", FormatNumber(wall_s)),
      Field("us_per_step", FormatNumber(done > 0 ? 1e6 * wall_s / done : 0.0)),
      Field("real_time_factor", FormatNumber(wall_s > 0 ? done * c.h / wall_s : 0.0)),
      Field("max_penetration", FormatNumber(max_penetration)),
      Field("mean_iterations", FormatNumber(done > 0 ? iterations / done : 0.0)),
      Field("kinetic_energy_initial", FormatNumber(kinetic_energy_initial)),
      Field("kinetic_energy_final", FormatNumber(KineticEnergy(m, d, d->qvel))),
      Field("engine", Quoted("mujoco")),
      Field("mujoco_version", Quoted(mj_versionString())),
      Field("solver", Quoted(m->opt.solver == mjSOL_CG ? "CG" : m->opt.solver == mjSOL_NEWTON ? "Newton" : "PGS")),
      Field("max_contacts", std::to_string(max_contacts)),
      Field("contact_overflows", std::to_string(overflows)),
  };
  for (const std::string& field : metrics.JsonFields()) fields.push_back(field);
  std::string line = "{";
  for (size_t i = 0; i < fields.size(); ++i) line += (i ? ", " : "") + fields[i];
  std::cout << line << "}" << std::endl;
}

double ParseNumber(const std::string& flag, const std::string& text, double low, double high) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !(value >= low && value <= high)) {
    throw std::invalid_argument(flag + " must be a number in [" + FormatNumber(low) + ", " + FormatNumber(high) +
                                "], got '" + text + "'");
  }
  return value;
}

int ParseInteger(const std::string& flag, const std::string& text, double low, double high) {
  const int value = static_cast<int>(ParseNumber(flag, text, low, high));
  if (std::to_string(value) != text) throw std::invalid_argument(flag + " must be an integer, got '" + text + "'");
  return value;
}

// The cases the flags select (implicit_sim_bench's rules); throws std::invalid_argument for bad flags.
std::vector<Case> SelectCases(std::map<std::string, std::string> values) {
  const bool s1_flags =
      values.count("--shape") || values.count("--n") || values.count("--seed") || values.count("--e-r");
  if (!values.count("--scenario")) {
    if (s1_flags || values.count("--duration") || values.count("--dt") || values.count("--variant")) {
      throw std::invalid_argument("--shape, --n, --seed, --e-r, --variant, --duration and --dt need --scenario");
    }
    return AllCases();
  }
  const std::string scenario = values["--scenario"];
  Case c;
  if (scenario == "S1") {
    if (values.count("--variant")) throw std::invalid_argument("--variant applies to P1, P2 and P3 only");
    const std::string shape = values.count("--shape") ? values["--shape"] : "sphere";
    if (shape != "sphere" && shape != "ellipsoid") {
      throw std::invalid_argument("--shape must be sphere or ellipsoid, got '" + shape + "'");
    }
    const int n = values.count("--n") ? ParseInteger("--n", values["--n"], 1, 100000) : 100;
    const unsigned seed = values.count("--seed") ? static_cast<unsigned>(ParseInteger("--seed", values["--seed"], 0, 2e9))
                                                 : 42u;
    c = Case{"S1", shape + "_n" + std::to_string(n), 0.005, 2.0, "",
             shape == "sphere" ? PileShape::kSphere : PileShape::kEllipsoid, n, seed};
    if (values.count("--e-r")) {
      c.e_r = ParseNumber("--e-r", values["--e-r"], 0.0, 1000.0);
      if (c.e_r != kPileTorsionLever) c.variant += "_er" + FormatNumber(c.e_r);
    }
  } else {
    if (s1_flags) throw std::invalid_argument("--shape, --n, --seed and --e-r apply to --scenario S1 only");
    bool found = false;
    for (const Case& known : AllCases()) {
      const bool variant_ok = !values.count("--variant") || known.variant == values["--variant"];
      if (known.scenario == scenario && variant_ok && !found) c = known, found = true;
    }
    if (!found) throw std::invalid_argument("no case --scenario '" + scenario + "' (P1, P2, P3, S1) with that variant");
  }
  if (values.count("--duration")) c.duration = ParseNumber("--duration", values["--duration"], 1e-6, 1e6);
  if (values.count("--dt")) c.h = ParseNumber("--dt", values["--dt"], 1e-6, 1.0);
  return {c};
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> flags = {"--scenario", "--variant", "--shape",      "--n",         "--seed",
                                          "--duration", "--dt",      "--max-wall", "--scenes-dir", "--solver", "--e-r"};
  std::map<std::string, std::string> values;
  std::vector<Case> cases;
  double max_wall_s = 300.0;  // s of time inside mj_step per run
  std::string solver;         // empty: Newton for P1-P3, CG for S1
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string flag = argv[i];
      if (std::find(flags.begin(), flags.end(), flag) == flags.end() || i + 1 >= argc) {
        throw std::invalid_argument("bad argument '" + flag + "' (flags: bench/README.md#side-by-side-with-mujoco)");
      }
      values[flag] = argv[++i];
    }
    if (values.count("--max-wall")) max_wall_s = ParseNumber("--max-wall", values["--max-wall"], 1e-3, 1e7);
    if (values.count("--solver")) {
      solver = values["--solver"];
      if (solver != "Newton" && solver != "CG" && solver != "PGS") {
        throw std::invalid_argument("--solver must be Newton, CG or PGS, got '" + solver + "'");
      }
    }
    values.erase("--max-wall"), values.erase("--solver");
    const std::string scenes_dir = values.count("--scenes-dir") ? values["--scenes-dir"] : IMPLICIT_SIM_SCENES_DIR;
    values.erase("--scenes-dir");
    cases = SelectCases(values);
    values["--scenes-dir"] = scenes_dir;
  } catch (const std::exception& e) {
    std::cerr << "implicit_sim_mujoco_bench: " << e.what() << "\n";
    return 2;
  }
  mju_user_warning = WarningToStderr;
  mju_user_error = ErrorToStderr;
  try {
    for (const Case& c : cases) Run(c, values["--scenes-dir"], max_wall_s, solver);
  } catch (const std::exception& e) {
    std::cerr << "implicit_sim_mujoco_bench: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
