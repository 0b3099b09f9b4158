#include "app/sweep/sweep.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "app/validation/plot_svg.h"
#include "app/rehearse/rehearsal.h"
#include "app/log/resimulation.h"
#include "app/log/session_recorder.h"
#include "app/state/parallel_for.h"
#include "sim/command_check.h"
#include "sim/command_file.h"
#include "sim/flight_rules.h"
#include "sim/model_loader.h"
#include "sim/random.h"
#include "sim/terrain_file.h"
#include "sim/text.h"

namespace sp {
namespace fs = std::filesystem;

namespace {

constexpr const char* kManifestHeader = "# SimPartner sweep manifest, version 1";
constexpr int kMaxSamples = 100000;

std::string manifestPath(const std::string& dir) { return dir + "/manifest.txt"; }
std::string resultPath(const std::string& dir, int i) { return dir + "/results/" + std::to_string(i) + ".tsv"; }
std::string statusPath(const std::string& dir, int i) { return dir + "/status/" + std::to_string(i); }

// Whether `key` takes only whole numbers (a fractional value is refused).
bool integerKey(const std::string& key) {
  SimParams probe;
  Diagnostics diag;
  return !applyOverride(probe, key + "=0.5", diag) && applyOverride(probe, key + "=1", diag);
}

// Sample i's seed: the sweep's seed and i alone (splitmix64 of their sum).
uint64_t sampleSeed(uint64_t seed, int index) {
  uint64_t z = seed + 0x9e3779b97f4a7c15ULL * static_cast<uint64_t>(index + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// The rehearsal a sample runs: the spec's files, its overrides, then the
// sample's own values; perturbed by its seed when the spec says so.
bool samplePlan(const SweepSpec& spec, const std::vector<std::string>& sets, uint64_t seed, RehearsalPlan& plan,
                std::string& error) {
  Diagnostics diag;
  std::optional<WorldModel> world = loadWorld(spec.world, diag);
  if (world && world->robots.empty()) diag.error(spec.world, 0, "the world has no robot to rehearse");
  SimParams params;
  if (!spec.params.empty()) loadParams(spec.params, params, diag);
  for (const std::string& o : spec.overrides) applyOverride(params, o, diag);
  for (const std::string& o : sets) applyOverride(params, o, diag);
  FlightRules rules;
  if (!spec.rules.empty()) loadFlightRules(spec.rules, rules, diag);
  std::optional<std::vector<TimedCommand>> commands;
  if (world && !world->robots.empty()) {
    commands = loadCommandSequence(spec.commands, diag, &world->robots[0].model);
    if (commands) checkCommands(*commands, *world, spec.commands, diag);
  }
  if (diag.hasErrors() || !world || !commands) {
    error = diag.format();
    if (!error.empty() && error.back() == '\n') error.pop_back();
    return false;
  }
  plan = RehearsalPlan{*world, params, rules, *commands, spec.start};
  plan.estimate = spec.estimate;
  if (spec.perturb) plan = perturbed(plan, seed);
  return true;
}

// Parses "key<TAB>value" lines.
std::map<std::string, std::string> readTsv(const std::string& path) {
  std::map<std::string, std::string> out;
  std::istringstream in(readWholeFile(path));
  for (std::string line; std::getline(in, line);) {
    const size_t tab = line.find('\t');
    if (tab != std::string::npos) out[line.substr(0, tab)] = line.substr(tab + 1);
  }
  return out;
}

std::string csvField(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string joinIndices(const std::vector<int>& v) {
  std::string out;
  for (int i : v) out += (out.empty() ? "" : ", ") + std::to_string(i);
  return out;
}

}  // namespace

std::string parseVary(const std::string& text, SweepVary& out) {
  const size_t eq = text.find('='), colon = text.find(':', eq == std::string::npos ? 0 : eq);
  if (eq == std::string::npos || eq == 0 || colon == std::string::npos)
    return "--vary " + text + ": expected KEY=LO:HI, e.g. ghost.step=0.002:0.004";
  const std::string lo = text.substr(eq + 1, colon - eq - 1), hi = text.substr(colon + 1);
  char* end = nullptr;
  out.key = text.substr(0, eq);
  out.lo = std::strtod(lo.c_str(), &end);
  const bool loOk = !lo.empty() && *end == '\0';
  out.hi = std::strtod(hi.c_str(), &end);
  const bool hiOk = !hi.empty() && *end == '\0';
  if (!loOk || !hiOk || !std::isfinite(out.lo) || !std::isfinite(out.hi) || std::abs(out.lo) > 1e6 ||
      std::abs(out.hi) > 1e6)
    return "--vary " + text + ": LO and HI must be numbers within +-1e6";
  if (out.lo > out.hi) return "--vary " + text + ": LO is above HI";
  return {};
}

bool createSweep(const std::string& dir, const SweepSpec& given, std::string& error) {
  SweepSpec spec = given;
  if (spec.samples < 1 || spec.samples > kMaxSamples) {
    error = "--samples: expected 1.." + std::to_string(kMaxSamples) + ", got " + std::to_string(spec.samples);
    return false;
  }
  std::error_code ec;
  for (std::string* path : {&spec.world, &spec.commands, &spec.rules, &spec.params})
    if (!path->empty()) *path = fs::absolute(*path, ec).lexically_normal().string();
  // Every value a sample can draw must be accepted: the range's ends.
  for (const SweepVary& v : spec.vary)
    for (double x : {v.lo, v.hi}) {
      SimParams probe;
      Diagnostics diag;
      if (!applyOverride(probe, v.key + "=" + shortestText(x), diag)) {
        error = "--vary " + v.key + ": " + diag.format();
        if (error.back() == '\n') error.pop_back();
        return false;
      }
    }
  std::vector<bool> integers;
  for (const SweepVary& v : spec.vary) {
    integers.push_back(integerKey(v.key));
    if (integers.back() && (v.lo != std::floor(v.lo) || v.hi != std::floor(v.hi))) {
      error = "--vary " + v.key + ": takes whole numbers; LO and HI must be whole";
      return false;
    }
  }
  RehearsalPlan plan;
  if (!samplePlan(spec, {}, spec.seed, plan, error)) return false;
  if (fs::exists(manifestPath(dir))) {
    error = manifestPath(dir) + ": a sweep is there already (collect it, or choose another --out)";
    return false;
  }
  fs::create_directories(dir + "/results", ec);
  if (!ec) fs::create_directories(dir + "/status", ec);
  if (ec) {
    error = dir + ": cannot create the sweep's folders: " + ec.message();
    return false;
  }
  std::ostringstream m;
  m << kManifestHeader << "\n"
    << "world " << spec.world << "\n"
    << "commands " << spec.commands << "\n"
    << "rules " << (spec.rules.empty() ? "-" : spec.rules) << "\n"
    << "params " << (spec.params.empty() ? "-" : spec.params) << "\n";
  for (const std::string& o : spec.overrides) m << "set " << o << "\n";
  for (const SweepVary& v : spec.vary) m << "vary " << v.key << " " << shortestText(v.lo) << " " << shortestText(v.hi) << "\n";
  m << "samples " << spec.samples << "\n"
    << "seed " << spec.seed << "\n"
    << "perturb " << (spec.perturb ? "true" : "false") << "\n";
  if (spec.estimate)
    for (size_t i = 0; i < kCalParams; ++i)
      m << "estimate " << calParams()[i].key << " " << shortestText(spec.estimate->sigma[i]) << " "
        << (spec.estimate->observed[i] ? "observed" : "prior") << "\n";
  if (spec.start) {
    const RehearsalStart& s = *spec.start;
    const auto numbers = [&](const char* key, std::initializer_list<double> values) {
      m << key;
      for (double v : values) m << " " << shortestText(v);
      m << "\n";
    };
    numbers("start_base", {s.base.p.x, s.base.p.y, s.base.p.z, s.base.q.w, s.base.q.x, s.base.q.y, s.base.q.z});
    numbers("start_twist", {s.baseLinear.x, s.baseLinear.y, s.baseLinear.z, s.baseAngular.x, s.baseAngular.y,
                            s.baseAngular.z});
    m << "start_joints";
    for (double v : s.jointPositions) m << " " << shortestText(v);
    m << "\nstart_rates";
    for (double v : s.jointRates) m << " " << shortestText(v);
    m << "\n";
    for (const auto& [name, pose] : s.objects)
      m << "start_object " << name << " " << shortestText(pose.p.x) << " " << shortestText(pose.p.y) << " " << shortestText(pose.p.z) << " "
        << shortestText(pose.q.w) << " " << shortestText(pose.q.x) << " " << shortestText(pose.q.y) << " " << shortestText(pose.q.z) << "\n";
  }
  for (int i = 0; i < spec.samples; ++i) {
    const uint64_t seed = spec.consecutiveSeeds ? spec.seed + static_cast<uint64_t>(i) : sampleSeed(spec.seed, i);
    Random draw(seed);
    m << "sample " << i << " " << seed;
    for (const SweepVary& v : spec.vary) {
      const double u = draw.uniform();
      // Integer keys (physics.iterations) draw each whole number alike.
      const double x = integers[&v - spec.vary.data()] ? std::floor(v.lo + (v.hi - v.lo + 1) * u) : v.lo + (v.hi - v.lo) * u;
      m << " --set " << v.key << "=" << shortestText(std::min(x, v.hi));
    }
    m << "\n";
  }
  return writeFileAtomically(manifestPath(dir), m.str(), error);
}

bool createSweepFromPlan(const std::string& dir, const RehearsalPlan& plan, uint64_t seed, std::string& error) {
  if (plan.world.robots.empty()) {
    error = "the plan's world has no robot";
    return false;
  }
  if (fs::exists(manifestPath(dir))) {
    error = manifestPath(dir) + ": a sweep is there already (choose another folder)";
    return false;
  }
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) {
    error = dir + ": cannot create: " + ec.message();
    return false;
  }
  SweepSpec spec;
  spec.world = plan.world.file;
  spec.commands = dir + "/sequence.seq";
  spec.rules = dir + "/flight.rules";
  spec.params = dir + "/sweep.params";
  spec.samples = plan.rules.robustSamples;
  spec.seed = seed;
  spec.start = plan.start;
  spec.consecutiveSeeds = true;
  spec.estimate = plan.estimate;
  std::string params = "# The console's parameters when the sweep was made\n";
  for (const ParamInfo& p : paramTable()) params += p.key + " = " + paramValue(plan.params, p.key) + "\n";
  const std::string sequence = "# The rehearsed sequence, as the console relays it\n" +
                               sequenceText(plan.commands, &plan.world.robots[0].model);
  if (!writeFileAtomically(spec.commands, sequence, error) ||
      !writeFileAtomically(spec.rules, flightRulesText(plan.rules), error) ||
      !writeFileAtomically(spec.params, params, error))
    return false;
  // The console's ground, edits included: a heightfield is saved exactly.
  if (plan.world.terrain.kind == TerrainSpec::Kind::Heightfield) {
    spec.world = dir + "/world.world.xml";
    if (!saveHeightGrid(dir + "/terrain.asc", plan.world.terrain.grid, error) ||
        !saveWorldWithTerrain(plan.world.file, spec.world, dir + "/terrain.asc", plan.world.terrain.grid, error))
      return false;
  }
  return createSweep(dir, spec, error);
}

bool readSweep(const std::string& dir, SweepSpec& spec, std::vector<SweepSample>& samples, std::string& error) {
  const std::string path = manifestPath(dir);
  std::ifstream in(path);
  if (!in) {
    error = path + ": cannot read the sweep's manifest";
    return false;
  }
  spec = {};
  samples.clear();
  int lineNo = 0;
  const auto fail = [&](const std::string& why) {
    error = path + ":" + std::to_string(lineNo) + ": error: " + why;
    return false;
  };
  for (std::string line; std::getline(in, line);) {
    ++lineNo;
    if (lineNo == 1) {
      if (line != kManifestHeader) return fail("not a SimPartner sweep manifest (version 1)");
      continue;
    }
    std::istringstream s(line);
    std::string word;
    s >> word;
    std::string rest;
    std::getline(s >> std::ws, rest);
    if (word == "world") spec.world = rest;
    else if (word == "commands") spec.commands = rest;
    else if (word == "rules") spec.rules = rest == "-" ? "" : rest;
    else if (word == "params") spec.params = rest == "-" ? "" : rest;
    else if (word == "set") spec.overrides.push_back(rest);
    else if (word == "vary") {
      SweepVary v;
      std::istringstream r(rest);
      if (!(r >> v.key >> v.lo >> v.hi)) return fail("expected: vary KEY LO HI");
      spec.vary.push_back(v);
    } else if (word == "samples") {
      if (!(std::istringstream(rest) >> spec.samples) || spec.samples < 1 || spec.samples > kMaxSamples)
        return fail("samples: expected 1.." + std::to_string(kMaxSamples));
    } else if (word == "seed") {
      if (!(std::istringstream(rest) >> spec.seed)) return fail("seed: expected an unsigned integer");
    } else if (word == "perturb") {
      if (rest != "true" && rest != "false") return fail("perturb: expected true or false");
      spec.perturb = rest == "true";
    } else if (word == "estimate") {
      std::istringstream r(rest);
      std::string key, kind;
      double sigma = 0;
      if (!(r >> key >> sigma >> kind) || !(kind == "observed" || kind == "prior"))
        return fail("expected: estimate KEY SIGMA observed|prior");
      const auto& table = calParams();
      const auto it = std::find_if(table.begin(), table.end(), [&](const CalParamInfo& c) { return key == c.key; });
      if (it == table.end()) return fail("estimate: '" + key + "' is not a calibration.* parameter");
      if (!std::isfinite(sigma) || sigma < 0) return fail("estimate " + key + ": the deviation must be finite and >= 0");
      if (!spec.estimate) spec.estimate = RobotEstimate{};
      const size_t i = static_cast<size_t>(it - table.begin());
      spec.estimate->sigma[i] = sigma;
      spec.estimate->observed[i] = kind == "observed";
    } else if (word.rfind("start_", 0) == 0) {
      if (!spec.start) spec.start = RehearsalStart{};
      RehearsalStart& st = *spec.start;
      std::istringstream r(rest);
      std::vector<double> v;
      std::string name;
      if (word == "start_object" && !(r >> name)) return fail("expected: start_object NAME x y z qw qx qy qz");
      for (double x; r >> x;) v.push_back(x);
      if (!r.eof()) return fail(word + ": expected numbers");
      if (word == "start_base" && v.size() == 7) {
        st.base = {{v[0], v[1], v[2]}, {v[3], v[4], v[5], v[6]}};
      } else if (word == "start_twist" && v.size() == 6) {
        st.baseLinear = {v[0], v[1], v[2]};
        st.baseAngular = {v[3], v[4], v[5]};
      } else if (word == "start_joints") {
        st.jointPositions = v;
      } else if (word == "start_rates") {
        st.jointRates = v;
      } else if (word == "start_object" && v.size() == 7) {
        st.objects.emplace_back(name, Pose{{v[0], v[1], v[2]}, {v[3], v[4], v[5], v[6]}});
      } else {
        return fail(word + ": unknown, or the wrong count of numbers");
      }
    } else if (word == "sample") {
      SweepSample sample;
      std::istringstream r(rest);
      if (!(r >> sample.index >> sample.seed) || sample.index != static_cast<int>(samples.size()))
        return fail("expected: sample " + std::to_string(samples.size()) + " SEED [--set KEY=VALUE]...");
      for (std::string flag, value; r >> flag;) {
        if (flag != "--set" || !(r >> value)) return fail("expected --set KEY=VALUE after the seed");
        sample.sets.push_back(value);
      }
      samples.push_back(std::move(sample));
    } else if (!word.empty()) {
      return fail("unknown line '" + word + "'");
    }
  }
  if (spec.world.empty() || spec.commands.empty()) return fail("no world or commands line");
  if (static_cast<int>(samples.size()) != spec.samples)
    return fail("the manifest lists " + std::to_string(samples.size()) + " samples of " +
                std::to_string(spec.samples) + " (cut short?)");
  return true;
}

bool runSweepTask(const std::string& dir, int index, std::string& error) {
  SweepSpec spec;
  std::vector<SweepSample> samples;
  if (!readSweep(dir, spec, samples, error)) return false;
  if (index < 0 || index >= static_cast<int>(samples.size())) {
    error = "task " + std::to_string(index) + ": the sweep has samples 0.." + std::to_string(samples.size() - 1);
    return false;
  }
  const SweepSample& sample = samples[static_cast<size_t>(index)];
  std::string statusError;
  const auto finish = [&](bool ok) {
    writeFileAtomically(statusPath(dir, index), ok ? "ok\n" : "error: " + error + "\n", statusError);
    return ok;
  };
  RehearsalPlan plan;
  if (!samplePlan(spec, sample.sets, sample.seed, plan, error)) return finish(false);
  const RehearsalResult r = rehearse(plan);
  if (!r.error.empty()) {
    error = r.error;
    return finish(false);
  }
  // The stability rule's closest approach: the least margin.
  double minMargin = std::numeric_limits<double>::quiet_NaN();
  for (const RuleVerdict& v : r.verdicts)
    if (v.rule == Rule::Stability) minMargin = v.worst;
  const RehearsalSample end = r.path.empty() ? RehearsalSample{} : r.path.back();
  std::string health = "healthy";
  for (const RuleVerdict& v : r.verdicts)
    if (v.rule == Rule::Health && !v.passed) health = v.message();
  std::ostringstream t;
  t << "index\t" << index << "\n"
    << "seed\t" << sample.seed << "\n";
  for (const std::string& set : sample.sets) {
    const size_t eq = set.find('=');
    t << "vary." << set.substr(0, eq) << "\t" << set.substr(eq + 1) << "\n";
  }
  t << "passed\t" << (r.passed ? "true" : "false") << "\n"
    << "summary\t" << r.summary() << "\n"
    << "end_x\t" << shortestText(end.base.p.x) << "\n"
    << "end_y\t" << shortestText(end.base.p.y) << "\n"
    << "end_heading_deg\t" << shortestText(radToDeg(heading(end.base.q))) << "\n"
    << "min_margin\t" << shortestText(minMargin) << "\n"
    << "health\t" << health << "\n"
    << "hash\t" << hashHex(r.endHash) << "\n"
    << "simulated_s\t" << shortestText(r.duration) << "\n"
    << "wall_s\t" << shortestText(r.wallSeconds) << "\n";
  if (!writeFileAtomically(resultPath(dir, index), t.str(), error)) return finish(false);
  return finish(true);
}

std::vector<int> pendingTasks(const std::string& dir, std::string& error) {
  SweepSpec spec;
  std::vector<SweepSample> samples;
  std::vector<int> out;
  if (!readSweep(dir, spec, samples, error)) return out;
  for (const SweepSample& s : samples)
    if (readWholeFile(statusPath(dir, s.index)) != "ok\n") out.push_back(s.index);
  return out;
}

bool runSweepLocal(const std::string& dir, std::vector<int> indices, int threads, std::string& error) {
  if (indices.empty()) {
    indices = pendingTasks(dir, error);
    if (!error.empty()) return false;
  }
  parallelFor(indices.size(), threads, [&](size_t k) {
    std::string taskError;
    runSweepTask(dir, indices[k], taskError);  // its status file says how it went
    return true;
  });
  return true;
}

std::string slurmArrayList(std::vector<int> indices) {
  std::sort(indices.begin(), indices.end());
  indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
  std::string out;
  for (size_t i = 0; i < indices.size();) {
    size_t j = i;
    while (j + 1 < indices.size() && indices[j + 1] == indices[j] + 1) ++j;
    out += (out.empty() ? "" : ",") + std::to_string(indices[i]);
    if (j > i) out += "-" + std::to_string(indices[j]);
    i = j + 1;
  }
  return out;
}

namespace {

// Single quotes for sh: nothing inside is special but the quote itself.
std::string shellQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

bool writeSlurmScript(const std::string& dir, const std::string& simBinary, std::string& error) {
  std::error_code ec;
  const std::string absDir = fs::absolute(dir, ec).lexically_normal().string();
  const std::string absSim = fs::absolute(simBinary, ec).lexically_normal().string();
  fs::create_directories(absDir + "/logs", ec);
  if (ec) {
    error = absDir + "/logs: cannot create: " + ec.message();
    return false;
  }
  const std::string script = "#!/bin/sh\n"
                             "# A SimPartner sweep as a Slurm job array (docs/sweeps.md). Each task runs one\n"
                             "# sample of manifest.txt, chosen by SLURM_ARRAY_TASK_ID, and writes its result\n"
                             "# and status files into this folder; the array's indices are given to sbatch.\n"
                             "#SBATCH --job-name=simpartner-sweep\n"
                             "#SBATCH --ntasks=1\n"
                             "#SBATCH --cpus-per-task=1\n"
                             "#SBATCH --output=" + absDir + "/logs/%a.out\n"
                             "exec " + shellQuote(absSim) + " sweep-task " + shellQuote(absDir) + "\n";
  if (!writeFileAtomically(absDir + "/sweep.sbatch", script, error)) return false;
  fs::permissions(absDir + "/sweep.sbatch", fs::perms::owner_exec, fs::perm_options::add, ec);
  return true;
}

std::string submitSlurm(const std::string& dir, std::vector<int> indices, const std::string& simBinary,
                        const std::vector<std::string>& sbatchArgs, std::string& error) {
  if (indices.empty()) {
    indices = pendingTasks(dir, error);
    if (!error.empty()) return {};
    if (indices.empty()) {
      error = dir + ": every task has run (nothing to submit)";
      return {};
    }
  }
  if (!writeSlurmScript(dir, simBinary, error)) return {};
  std::error_code ec;
  std::string command = "sbatch --parsable --array=" + slurmArrayList(indices);
  for (const std::string& a : sbatchArgs) command += " " + shellQuote(a);
  command += " " + shellQuote(fs::absolute(dir, ec).lexically_normal().string() + "/sweep.sbatch") + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) {
    error = "cannot run sbatch";
    return {};
  }
  std::string out;
  char buffer[256];
  while (std::fgets(buffer, sizeof buffer, pipe)) out += buffer;
  const int status = pclose(pipe);
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  const std::string id = out.substr(0, out.find(';'));  // "jobid;cluster" on federated clusters
  if (status != 0 || id.empty() || id.find_first_not_of("0123456789") != std::string::npos) {
    error = "sbatch failed: " + (out.empty() ? std::string("no output (is Slurm installed?)") : out);
    return {};
  }
  return id;
}

SweepSummary collectSweep(const std::string& dir, std::string& error) {
  SweepSummary sum;
  SweepSpec spec;
  std::vector<SweepSample> samples;
  if (!readSweep(dir, spec, samples, error)) return sum;
  sum.samples = static_cast<int>(samples.size());
  std::ostringstream csv;
  csv << "index,seed";
  for (const SweepVary& v : spec.vary) csv << "," << v.key;
  csv << ",passed,summary,end_x,end_y,end_heading_deg,min_margin,health,hash,wall_s\n";
  PlotSeries ok{"passed", {}, {}, PlotSeries::Style::Points}, bad{"failed a rule", {}, {}, PlotSeries::Style::Points};
  PlotSeries margins{"least stability margin", {}, {}, PlotSeries::Style::Points};
  std::vector<std::string> failures;
  for (const SweepSample& s : samples) {
    const std::string status = readWholeFile(statusPath(dir, s.index));
    if (status.empty()) {
      sum.missing.push_back(s.index);
      continue;
    }
    if (status != "ok\n") {
      sum.failed.push_back(s.index);
      failures.push_back("task " + std::to_string(s.index) + ": " + status.substr(0, status.size() - 1));
      continue;
    }
    std::map<std::string, std::string> r = readTsv(resultPath(dir, s.index));
    ++sum.done;
    const bool passed = r["passed"] == "true";
    sum.passed += passed;
    csv << s.index << "," << s.seed;
    for (const SweepVary& v : spec.vary) csv << "," << r["vary." + v.key];
    csv << "," << r["passed"] << "," << csvField(r["summary"]) << "," << r["end_x"] << "," << r["end_y"] << ","
        << r["end_heading_deg"] << "," << r["min_margin"] << "," << csvField(r["health"]) << "," << r["hash"] << ","
        << r["wall_s"] << "\n";
    margins.x.push_back(s.index);
    margins.y.push_back(std::strtod(r["min_margin"].c_str(), nullptr));
    PlotSeries& series = passed ? ok : bad;
    series.x.push_back(std::strtod(r["end_x"].c_str(), nullptr));
    series.y.push_back(std::strtod(r["end_y"].c_str(), nullptr));
  }
  if (!writeFileAtomically(dir + "/results.csv", csv.str(), error)) return sum;
  PlotSpec plot{"Sweep: where each sample ended", "x [m]", "y [m]", {}, 720, 720, {}, {}};
  for (const PlotSeries& series : {ok, bad})
    if (!series.x.empty()) plot.series.push_back(series);
  if (plot.series.empty()) plot.series.push_back({"no sample has run", {0}, {0}, PlotSeries::Style::Points});
  if (!writePlotSvg(plot, dir + "/end_positions.svg", error)) return sum;
  PlotSpec marginPlot{"Sweep: least stability margin of each sample", "sample", "margin [m]", {}, 960, 400, {}, {}};
  marginPlot.series.push_back(margins.x.empty() ? PlotSeries{"no sample has run", {0}, {0}, PlotSeries::Style::Points}
                                                 : margins);
  if (!writePlotSvg(marginPlot, dir + "/margins.svg", error)) return sum;
  std::ostringstream md;
  md << "# Sweep " << fs::path(dir).filename().string() << "\n\n"
     << "`" << spec.commands << "` on `" << spec.world << "`, " << spec.samples << " samples, seed " << spec.seed
     << (!spec.perturb    ? ""
         : spec.estimate ? ", each robot drawn from what the console knows of it (the calibration's estimate)"
                         : ", each perturbed within the rules' robustness ranges")
     << ".\n";
  for (const SweepVary& v : spec.vary) md << "- `" << v.key << "` drawn in [" << shortestText(v.lo) << ", " << shortestText(v.hi) << "]\n";
  md << "\n**" << sum.passed << " of " << sum.done << " samples that ran passed every rule**";
  if (sum.done) md << " (" << shortestText(std::round(1000.0 * sum.passed / sum.done) / 10) << " %)";
  md << ". Missing (never ran): " << (sum.missing.empty() ? "none" : joinIndices(sum.missing))
     << ". Failed to run: " << (sum.failed.empty() ? "none" : joinIndices(sum.failed)) << ".\n\n";
  for (const std::string& f : failures) md << "- " << f << "\n";
  if (!sum.missing.empty() || !sum.failed.empty())
    md << "\nRun only those again: `simpartner-sim sweep --resume " << dir << "` (add `--slurm` on a cluster).\n";
  md << "\n![End positions](end_positions.svg)\n\n![Least stability margins](margins.svg) (data: "
        "[results.csv](results.csv))\n";
  writeFileAtomically(dir + "/report.md", md.str(), error);
  return sum;
}

}  // namespace sp
