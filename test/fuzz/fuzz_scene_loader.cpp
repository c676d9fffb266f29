// A seeded random-mutation fuzzer for the scene loader (g++ has no libFuzzer). It mutates a corpus of URDF scenes
// (byte flips, inserts, deletes, splices between inputs, numbers replaced by nan/inf/-1/1e308/0/huge integers,
// XML elements and attributes duplicated or deleted, hostile mesh URIs inserted, chains of up to 500 links and up
// to 150 free bodies appended) and loads each input with LoadSceneFromString, meshes sandboxed as in the node.
//   std::invalid_argument        the expected refusal of a bad scene;
//   a returned Model             accepted;
//   any other exception          a failure;
//   a load over --timeout-ms     a failure (a load that hangs past --hang-ms is caught by a watchdog thread);
//   a crash or sanitizer report  a failure (built with -DIMPLICIT_SIM_SANITIZE=ON: a death callback saves the input);
//   a leak                       a failure (sanitized builds run LeakSanitizer every --leak-check-every inputs).
// A failing input is written to --out DIR as fuzz_<kind>_<index>.urdf. The last line printed is a JSON summary.
// Exit status: 0 when there was no failure. The input sequence depends on --seed only (not on timing), so
// `--seed S --max-inputs N` replays a run's first N inputs.
//
// Usage: implicit_sim_fuzz_loader [--seed N] [--seconds S] [--max-inputs N] [--timeout-ms T] [--hang-ms T]
//                                 [--out DIR] [--leak-check-every N] --corpus PATH...   (files or directories)
#include <dirent.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <iostream>
#include <iterator>
#include <mutex>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <console_bridge/console.h>

#include "implicit_sim/core/model/urdf_loader.h"

#if defined(__SANITIZE_ADDRESS__)  // g++
#define IMPLICIT_SIM_FUZZ_SANITIZED 1
#elif defined(__has_feature)       // clang
#if __has_feature(address_sanitizer)
#define IMPLICIT_SIM_FUZZ_SANITIZED 1
#endif
#endif
#ifdef IMPLICIT_SIM_FUZZ_SANITIZED
#include <sanitizer/common_interface_defs.h>
#include <sanitizer/lsan_interface.h>
#endif

namespace {

using Clock = std::chrono::steady_clock;

// Loads as the node's services do, with mesh files read only inside a sandbox: here one root that does not exist, so
// every mesh URI an input names must be refused (std::invalid_argument) without a file being opened.
const implicit_sim::LoaderOptions& SandboxedLoader() {
  static const implicit_sim::LoaderOptions options = [] {
    implicit_sim::LoaderOptions o;
    o.mesh_sandbox.roots = {"/nonexistent/implicit_sim_fuzz_meshes"};
    return o;
  }();
  return options;
}

struct Options {
  uint64_t seed = 1;
  double seconds = 10.0;
  long max_inputs = -1;  // -1: bounded by --seconds only
  double timeout_ms = 1000.0;
  double hang_ms = 10000.0;
  long leak_check_every = 200;
  std::string out = ".";
  std::vector<std::string> corpus_paths;
};

[[noreturn]] void Usage(const std::string& error) {
  std::cerr << "implicit_sim_fuzz_loader: " << error << "\n"
            << "usage: implicit_sim_fuzz_loader [--seed N] [--seconds S] [--max-inputs N] [--timeout-ms T]\n"
            << "       [--hang-ms T] [--out DIR] [--leak-check-every N] --corpus PATH...\n";
  std::exit(2);
}

Options ParseArgs(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) Usage(a + " needs a value");
      return argv[++i];
    };
    try {
      if (a == "--seed") {
        o.seed = std::stoull(value());
      } else if (a == "--seconds") {
        o.seconds = std::stod(value());
      } else if (a == "--max-inputs") {
        o.max_inputs = std::stol(value());
      } else if (a == "--timeout-ms") {
        o.timeout_ms = std::stod(value());
      } else if (a == "--hang-ms") {
        o.hang_ms = std::stod(value());
      } else if (a == "--leak-check-every") {
        o.leak_check_every = std::stol(value());
      } else if (a == "--out") {
        o.out = value();
      } else if (a == "--corpus") {
        // Every following argument up to the next option.
        while (i + 1 < argc && std::strncmp(argv[i + 1], "--", 2) != 0) o.corpus_paths.push_back(argv[++i]);
      } else if (a == "--help" || a == "-h") {
        Usage("help");
      } else {
        Usage("unknown argument '" + a + "'");
      }
    } catch (const std::logic_error&) {
      Usage("bad value for " + a);
    }
  }
  if (o.corpus_paths.empty()) Usage("no --corpus given");
  if (!(o.seconds > 0) || !(o.timeout_ms > 0) || !(o.hang_ms > 0)) Usage("--seconds, --timeout-ms, --hang-ms must be > 0");
  return o;
}

bool IsDirectory(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Files named on the command line, and the regular files directly inside named directories (sorted, so the corpus
// order and with it the input sequence do not depend on the directory listing).
std::vector<std::pair<std::string, std::string>> LoadCorpus(const std::vector<std::string>& paths) {
  std::vector<std::string> files;
  for (const std::string& p : paths) {
    if (!IsDirectory(p)) {
      files.push_back(p);
      continue;
    }
    std::vector<std::string> in_dir;
    if (DIR* d = ::opendir(p.c_str())) {
      while (const dirent* e = ::readdir(d)) {
        const std::string name = e->d_name;
        if (name == "." || name == "..") continue;
        const std::string full = p + "/" + name;
        if (!IsDirectory(full)) in_dir.push_back(full);
      }
      ::closedir(d);
    }
    std::sort(in_dir.begin(), in_dir.end());
    files.insert(files.end(), in_dir.begin(), in_dir.end());
  }
  std::vector<std::pair<std::string, std::string>> corpus;
  for (const std::string& f : files) {
    std::ifstream probe(f, std::ios::binary);
    if (!probe) {
      std::cerr << "implicit_sim_fuzz_loader: cannot read " << f << "\n";
      std::exit(2);
    }
    corpus.emplace_back(f, ReadFile(f));
  }
  return corpus;
}

// ---------------------------------------------------------------------------------------------------------------
// Mutations. Each takes the input and the generator; all positions are drawn from the generator only.

class Mutator {
 public:
  Mutator(uint64_t seed, const std::vector<std::string>* corpus) : rng_(seed), corpus_(corpus) {}

  size_t Below(size_t n) { return n == 0 ? 0 : std::uniform_int_distribution<size_t>(0, n - 1)(rng_); }
  bool Chance(double p) { return std::uniform_real_distribution<double>(0.0, 1.0)(rng_) < p; }

  std::string Mutate(std::string s) {
    const int count = 1 + static_cast<int>(Below(Chance(0.2) ? 8 : 3));
    for (int k = 0; k < count; ++k) {
      switch (Below(13)) {
        case 0: FlipBit(&s); break;
        case 1: InsertBytes(&s); break;
        case 2: DeleteRange(&s); break;
        case 3: Splice(&s); break;
        case 4:
        case 5:
        case 6: ReplaceNumber(&s); break;
        case 7: DuplicateOrDeleteElement(&s); break;
        case 8: DuplicateOrDeleteAttribute(&s); break;
        case 9: ReplaceAttributeValue(&s); break;
        case 10: InsertToken(&s); break;
        case 11: AppendChainOrBodies(&s); break;
        default: DuplicateRange(&s); break;
      }
    }
    return s;
  }

 private:
  void FlipBit(std::string* s) {
    if (s->empty()) return;
    (*s)[Below(s->size())] ^= static_cast<char>(1u << Below(8));
  }

  void InsertBytes(std::string* s) {
    static const char kInteresting[] = "<>/=\"' \n\t&;!?-0123456789.eE+xyzabc";
    const size_t n = 1 + Below(8);
    std::string bytes;
    for (size_t i = 0; i < n; ++i) {
      bytes += Chance(0.7) ? kInteresting[Below(sizeof(kInteresting) - 1)] : static_cast<char>(Below(256));
    }
    s->insert(Below(s->size() + 1), bytes);
  }

  void DeleteRange(std::string* s) {
    if (s->empty()) return;
    const size_t pos = Below(s->size());
    s->erase(pos, 1 + Below(Chance(0.8) ? 16 : 512));
  }

  void DuplicateRange(std::string* s) {
    if (s->empty()) return;
    const size_t pos = Below(s->size());
    const std::string chunk = s->substr(pos, 1 + Below(64));
    s->insert(Below(s->size() + 1), chunk);
  }

  // A chunk of another corpus input replaces a range of this one (or is inserted).
  void Splice(std::string* s) {
    const std::string& other = (*corpus_)[Below(corpus_->size())];
    if (other.empty()) return;
    const size_t from = Below(other.size());
    const std::string chunk = other.substr(from, 1 + Below(256));
    const size_t pos = Below(s->size() + 1);
    const size_t replace = Chance(0.5) ? std::min(s->size() - pos, Below(256)) : 0;
    s->replace(pos, replace, chunk);
  }

  static bool IsNumberChar(char c) { return (c >= '0' && c <= '9') || c == '.' || c == '-' || c == '+' || c == 'e'; }

  // The numeric tokens: maximal runs of [0-9.+-e] that contain a digit.
  static std::vector<std::pair<size_t, size_t>> Numbers(const std::string& s) {
    std::vector<std::pair<size_t, size_t>> out;
    size_t i = 0;
    while (i < s.size()) {
      if (!IsNumberChar(s[i])) {
        ++i;
        continue;
      }
      size_t j = i;
      bool digit = false;
      while (j < s.size() && IsNumberChar(s[j])) digit |= (s[j] >= '0' && s[j] <= '9'), ++j;
      if (digit) out.emplace_back(i, j - i);
      i = j;
    }
    return out;
  }

  void ReplaceNumber(std::string* s) {
    static const char* const kValues[] = {
        "nan", "NaN", "-nan", "inf", "-inf", "infinity", "-1", "1e308", "-1e308", "1e309", "1e-308", "4.9e-324",
        "0", "-0", "0.0", "1", "2", "3", "1e9", "2147483647", "2147483648", "-2147483648", "9223372036854775807",
        "99999999999999999999999", "1e-12", "0x10", "1,5", "", " ", "1 2", "1 2 3 4", "+", "-", ".", "e", "1e",
        "3.14159", "1e6", "100000", "4294967296"};
    const auto numbers = Numbers(*s);
    if (numbers.empty()) return;
    const auto& [pos, len] = numbers[Below(numbers.size())];
    std::string value = kValues[Below(sizeof(kValues) / sizeof(kValues[0]))];
    if (Chance(0.1)) {  // a random double, of any magnitude
      std::ostringstream v;
      v.precision(17);
      v << std::ldexp(std::uniform_real_distribution<double>(-1.0, 1.0)(rng_), static_cast<int>(Below(2100)) - 1050);
      value = v.str();
    }
    s->replace(pos, len, value);
  }

  // An element: from a start tag '<name' to the matching '/>' or the first '</name>' after it.
  bool PickElement(const std::string& s, size_t* begin, size_t* end) {
    std::vector<size_t> starts;
    for (size_t i = 0; i + 1 < s.size(); ++i) {
      if (s[i] == '<' && (std::isalpha(static_cast<unsigned char>(s[i + 1])) || s[i + 1] == '_')) starts.push_back(i);
    }
    if (starts.empty()) return false;
    const size_t b = starts[Below(starts.size())];
    size_t name_end = b + 1;
    while (name_end < s.size() && !std::isspace(static_cast<unsigned char>(s[name_end])) && s[name_end] != '>' &&
           s[name_end] != '/') {
      ++name_end;
    }
    const std::string name = s.substr(b + 1, name_end - b - 1);
    const size_t close = s.find('>', name_end);
    if (close == std::string::npos) return false;
    size_t e;
    if (s[close - 1] == '/') {
      e = close + 1;
    } else {
      const size_t end_tag = s.find("</" + name + ">", close);
      if (end_tag == std::string::npos) return false;
      e = end_tag + name.size() + 3;
    }
    *begin = b;
    *end = e;
    return true;
  }

  void DuplicateOrDeleteElement(std::string* s) {
    size_t b, e;
    if (!PickElement(*s, &b, &e)) return;
    const std::string element = s->substr(b, e - b);
    switch (Below(4)) {
      case 0: s->erase(b, e - b); break;                              // delete
      case 1: s->insert(e, element); break;                           // duplicate in place
      case 2: {                                                       // move/copy into another element
        size_t b2, e2;
        if (!PickElement(*s, &b2, &e2)) return;
        const size_t inner = s->find('>', b2);
        if (inner == std::string::npos || inner >= e2) return;
        s->insert(inner + 1, element);
        break;
      }
      default: {  // nest the element N times (depth)
        std::string nested = element;
        const int depth = 1 + static_cast<int>(Below(6));
        for (int i = 0; i < depth; ++i) nested += element;
        s->insert(e, nested);
        break;
      }
    }
  }

  // Attributes: ' name="value"' inside a tag.
  static std::vector<std::pair<size_t, size_t>> Attributes(const std::string& s) {
    std::vector<std::pair<size_t, size_t>> out;
    for (size_t i = 0; i < s.size(); ++i) {
      if (s[i] != '=' || i + 1 >= s.size() || s[i + 1] != '"') continue;
      size_t b = i;
      while (b > 0 && (std::isalnum(static_cast<unsigned char>(s[b - 1])) || s[b - 1] == '_' || s[b - 1] == ':')) --b;
      if (b == i || b == 0 || !std::isspace(static_cast<unsigned char>(s[b - 1]))) continue;
      const size_t close = s.find('"', i + 2);
      if (close == std::string::npos) continue;
      out.emplace_back(b - 1, close + 1 - (b - 1));
    }
    return out;
  }

  void DuplicateOrDeleteAttribute(std::string* s) {
    const auto attrs = Attributes(*s);
    if (attrs.empty()) return;
    const auto& [pos, len] = attrs[Below(attrs.size())];
    const std::string attr = s->substr(pos, len);
    switch (Below(3)) {
      case 0: s->erase(pos, len); break;
      case 1: s->insert(pos + len, attr); break;  // a duplicate attribute: tinyxml2 must refuse
      default: {                                  // copy it into another tag
        const auto& [pos2, len2] = attrs[Below(attrs.size())];
        s->insert(pos2 + len2, attr);
        break;
      }
    }
  }

  void ReplaceAttributeValue(std::string* s) {
    static const char* const kValues[] = {
        "world", "ball", "floating", "fixed", "revolute", "continuous", "prismatic", "planar", "sphere", "box",
        "cylinder", "ellipsoid", "superellipsoid", "ngon", "polygon", "prism", "halfspace", "half_space",
        "intersection", "", " ", "0 0 0", "1 1 1", "nan nan nan", "inf 0 0", "1e308 1e308 1e308", "-1 -1 -1",
        "0 0", "1 2 3 4", "y rx rz", "x y z rx ry rz", "q", "&amp;", "&#0;", "&#x110000;", "\xff\xfe"};
    const auto attrs = Attributes(*s);
    if (attrs.empty()) return;
    const auto& [pos, len] = attrs[Below(attrs.size())];
    const size_t quote = s->find('"', pos);
    std::string value;
    if (Chance(0.3)) {  // another attribute's value
      const auto& [pos2, len2] = attrs[Below(attrs.size())];
      const size_t q2 = s->find('"', pos2);
      value = s->substr(q2 + 1, pos2 + len2 - 1 - (q2 + 1));
    } else {
      value = kValues[Below(sizeof(kValues) / sizeof(kValues[0]))];
    }
    s->replace(quote + 1, pos + len - 1 - (quote + 1), value);
  }

  // Structure the byte mutations rarely build (issue 35's cases): a chain of up to 500 links on joints of every
  // kind, or up to 150 free bodies, appended before </robot> (the loader refuses them where 'world' is missing).
  void AppendChainOrBodies(std::string* s) {
    const size_t end = s->rfind("</robot>");
    if (end == std::string::npos) return;
    static const char* const kJointTypes[] = {"fixed", "revolute", "continuous", "prismatic"};
    const bool free_bodies = Chance(0.5);
    const size_t count = 1 + Below(free_bodies ? 150 : 500);
    std::string block;
    for (size_t i = 0; i < count; ++i) {
      const std::string link = "fz" + std::to_string(i);
      const std::string parent = free_bodies || i == 0 ? "world" : "fz" + std::to_string(i - 1);
      const std::string xyz = free_bodies ? std::to_string(0.1 * (i % 20)) + " " + std::to_string(0.1 * (i / 20)) + " 1"
                                          : std::string("0 0 0.01");
      block += "<link name=\"" + link + "\"><inertial><mass value=\"1\"/><inertia ixx=\"1e-3\" iyy=\"1e-3\" " +
               "izz=\"1e-3\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>" +
               (Chance(0.5) ? "<collision><geometry><sphere radius=\"0.004\"/></geometry></collision>" : "") +
               "</link><joint name=\"fzj" + std::to_string(i) + "\" type=\"" +
               (free_bodies ? "floating" : kJointTypes[Below(4)]) + "\"><parent link=\"" + parent +
               "\"/><child link=\"" + link + "\"/><origin xyz=\"" + xyz + "\"/><axis xyz=\"0 0 1\"/>" +
               "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>";
    }
    s->insert(end, block);
  }

  void InsertToken(std::string* s) {
    static const char* const kTokens[] = {
        "<link name=\"x\"/>", "<joint name=\"j\" type=\"floating\"><parent link=\"world\"/><child link=\"x\"/></joint>",
        "<collision><geometry><sphere radius=\"1\"/></geometry></collision>", "<implicit_sim/>", "<robot>",
        "</robot>", "<!--", "-->", "<![CDATA[", "]]>", "<?xml version=\"1.0\"?>", "&lt;", "&#65;", "\0",
        "<friction mu=\"0.5\"/>", "<body link=\"world\"/>", "<body link=\"nope\" locked=\"x\"/>", "<inertial/>",
        "<origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>", "<mass value=\"0\"/>", "<implicit type=\"ngon\" n=\"1000000\"/>",
        // Mesh URIs out of the sandbox the harness loads with (LoaderOptions::mesh_sandbox): each must be refused.
        "<collision><geometry><mesh filename=\"/etc/passwd\"/></geometry></collision>",
        "<collision><geometry><mesh filename=\"file:///proc/self/environ\"/></geometry></collision>",
        "<collision><geometry><mesh filename=\"/dev/zero\"/></geometry></collision>",
        "<collision><geometry><mesh filename=\"package://implicit_sim/../../../../../../etc/passwd\"/></geometry>"
        "</collision>",
        "<collision><geometry><mesh filename=\"../../../../../../etc/shadow\" scale=\"1 1 1\"/></geometry></collision>"};
    const size_t k = Below(sizeof(kTokens) / sizeof(kTokens[0]));
    const std::string token = kTokens[k][0] == '\0' ? std::string(1, '\0') : std::string(kTokens[k]);
    s->insert(Below(s->size() + 1), token);
  }

  std::mt19937_64 rng_;
  const std::vector<std::string>* corpus_;
};

// ---------------------------------------------------------------------------------------------------------------
// What a crash, a hang or a leak report needs: the input being loaded, kept where a death callback and the
// watchdog can reach it.

std::mutex g_mutex;
std::string g_current;  // the input being loaded (guarded by g_mutex)
long g_current_index = -1;
bool g_busy = false;
Clock::time_point g_start;
std::string g_out_dir = ".";

std::string FailurePath(const std::string& kind, long index) {
  return g_out_dir + "/fuzz_" + kind + "_" + std::to_string(index) + ".urdf";
}

// Writes with open/write only (called from the death callback and the watchdog, not from normal flow).
void WriteRaw(const std::string& path, const std::string& bytes) {
  if (FILE* f = std::fopen(path.c_str(), "wb")) {
    std::fwrite(bytes.data(), 1, bytes.size(), f);
    std::fclose(f);
  }
}

#ifdef IMPLICIT_SIM_FUZZ_SANITIZED
void OnSanitizerDeath() {
  // The sanitizer already printed its report; the input is not guarded here (the process is dying, and the main
  // thread is the one that failed).
  if (!g_busy) return;  // not while loading: a leak found at exit (its report names the allocation)
  const std::string path = FailurePath("crash", g_current_index);
  WriteRaw(path, g_current);
  std::fprintf(stderr, "implicit_sim_fuzz_loader: sanitizer failure on input %ld, written to %s\n", g_current_index,
               path.c_str());
}
#endif

std::string JsonEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += c;
    }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  const Options opt = ParseArgs(argc, argv);
  g_out_dir = opt.out;
  ::mkdir(opt.out.c_str(), 0755);
  // urdfdom logs every parse error through console_bridge: thousands of lines a second otherwise.
  console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_NONE);
#ifdef IMPLICIT_SIM_FUZZ_SANITIZED
  __sanitizer_set_death_callback(OnSanitizerDeath);
#endif

  const auto corpus_files = LoadCorpus(opt.corpus_paths);
  if (corpus_files.empty()) Usage("the corpus is empty");
  std::vector<std::string> corpus;
  for (const auto& f : corpus_files) corpus.push_back(f.second);
  // Inputs that were accepted join a bounded pool that later mutations start from: deeper mutants of valid scenes.
  std::vector<std::string> pool = corpus;
  const size_t kPoolMax = 256;

  std::atomic<bool> done{false};
  std::thread watchdog([&] {
    while (!done.load()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      std::lock_guard<std::mutex> lock(g_mutex);
      if (g_busy && std::chrono::duration<double, std::milli>(Clock::now() - g_start).count() > opt.hang_ms) {
        const std::string path = FailurePath("hang", g_current_index);
        WriteRaw(path, g_current);
        std::printf("{\"error\": \"input %ld hangs (over %.0f ms), written to %s\", \"failures\": 1}\n",
                    g_current_index, opt.hang_ms, JsonEscape(path).c_str());
        std::fflush(stdout);
        std::_Exit(3);
      }
    }
  });

  Mutator mutator(opt.seed, &corpus);
  long inputs = 0, accepted = 0, refused = 0, failures = 0, slow = 0, leak_checks = 0;
  double slowest_ms = 0.0;
  long slowest_index = -1;
  long last_leak_check = 0;
  std::vector<std::string> since_leak_check;  // the inputs since the last leak check (sanitized builds)
  const auto t0 = Clock::now();
  auto fail = [&](const std::string& kind, long index, const std::string& input, const std::string& what) {
    ++failures;
    const std::string path = FailurePath(kind, index);
    WriteRaw(path, input);
    std::cerr << "implicit_sim_fuzz_loader: FAILURE (" << kind << ") on input " << index << ": " << what
              << "; input written to " << path << "\n";
  };

  while (true) {
    const double elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
    if (opt.max_inputs >= 0 ? inputs >= opt.max_inputs : elapsed >= opt.seconds) break;
    if (opt.max_inputs >= 0 && elapsed >= opt.seconds) break;
    if (failures >= 10) break;  // enough to act on

    // The corpus first as it is, then mutants of the corpus or of the pool.
    std::string input = inputs < static_cast<long>(corpus.size())
                            ? corpus[inputs]
                            : mutator.Mutate(mutator.Chance(0.5) ? corpus[mutator.Below(corpus.size())]
                                                                 : pool[mutator.Below(pool.size())]);
    if (input.size() > (1u << 20)) input.resize(1u << 20);  // nested duplication grows inputs: keep them bounded
    const long index = inputs++;
    {
      std::lock_guard<std::mutex> lock(g_mutex);
      g_current = input;
      g_current_index = index;
      g_start = Clock::now();
      g_busy = true;
    }
    const auto start = Clock::now();
    std::string failure_kind, failure_what;
    try {
      const implicit_sim::Model model = implicit_sim::LoadSceneFromString(input, "fuzz", SandboxedLoader());
      ++accepted;
      if (pool.size() < kPoolMax) {
        pool.push_back(input);
      } else {
        pool[corpus.size() + mutator.Below(kPoolMax - corpus.size())] = input;
      }
    } catch (const std::invalid_argument&) {
      ++refused;
    } catch (const std::exception& e) {
      failure_kind = "exception";
      failure_what = std::string("unexpected exception: ") + e.what();
    } catch (...) {
      failure_kind = "exception";
      failure_what = "a non-std exception";
    }
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    {
      std::lock_guard<std::mutex> lock(g_mutex);
      g_busy = false;
    }
    if (ms > slowest_ms) slowest_ms = ms, slowest_index = index;
    if (!failure_kind.empty()) fail(failure_kind, index, input, failure_what);
    if (ms > opt.timeout_ms) {
      ++slow;
      fail("slow", index, input, "took " + std::to_string(ms) + " ms");
    }
#ifdef IMPLICIT_SIM_FUZZ_SANITIZED
    since_leak_check.push_back(input);
    if (opt.leak_check_every > 0 && inputs - last_leak_check >= opt.leak_check_every) {
      ++leak_checks;
      if (__lsan_do_recoverable_leak_check() != 0) {
        // Any of these inputs may have leaked: write them all (at most --leak-check-every files).
        for (size_t k = 0; k < since_leak_check.size(); ++k) {
          WriteRaw(FailurePath("leak", last_leak_check + static_cast<long>(k)), since_leak_check[k]);
        }
        ++failures;
        std::cerr << "implicit_sim_fuzz_loader: FAILURE (leak) among inputs " << last_leak_check << ".." << inputs - 1
                  << "; written to " << opt.out << "/fuzz_leak_*.urdf\n";
        break;  // later checks would report the same blocks again
      }
      since_leak_check.clear();
      last_leak_check = inputs;
    }
#else
    (void)last_leak_check;
#endif
  }
  done = true;
  watchdog.join();
  const double elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
  std::printf(
      "{\"seed\": %llu, \"seconds\": %.1f, \"corpus\": %zu, \"inputs\": %ld, \"inputs_per_s\": %.0f, \"accepted\": %ld, "
      "\"refused\": %ld, \"slowest_ms\": %.2f, \"slowest_input\": %ld, \"slow\": %ld, \"leak_checks\": %ld, "
      "\"sanitized\": %s, \"failures\": %ld}\n",
      static_cast<unsigned long long>(opt.seed), elapsed, corpus.size(), inputs, inputs / std::max(elapsed, 1e-9),
      accepted, refused, slowest_ms, slowest_index, slow, leak_checks,
#ifdef IMPLICIT_SIM_FUZZ_SANITIZED
      "true",
#else
      "false",
#endif
      failures);
  return failures == 0 ? 0 : 1;
}
