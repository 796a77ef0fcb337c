// Atomic outputs: a command that fails — bad input found after it started, an unwritable output,
// SIGINT or SIGTERM during the run or while the output is being written — leaves any previous
// output file byte-for-byte untouched and no temporary file behind. First the AtomicFileWriter /
// AtomicFileSet contract in-process (signals in a forked child), then the real CLI.

#include <signal.h>
#include <sys/inotify.h>
#include <sys/wait.h>
#include <unistd.h>

#include <poll.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "errfield/atomic_file.hpp"
#include "errfield/error.hpp"
#include "support/cli_test_common.hpp"

namespace errfield {
namespace atomic_output_test {

using namespace testing::cli_common;
using ::testing::ElementsAre;

constexpr const char* kOld = "previous output\n";

TEST(AtomicFileWriter, DestroyedWithoutCommitLeavesTargetAndNoTemporary) {
  ScratchDir dir;
  dir.write("out.csv", kOld);
  {
    AtomicFileWriter w(dir.path() / "out.csv");
    w.stream() << "half a new file";
    EXPECT_EQ(dir.entries().size(), 2u);  // the target and the temporary
  }
  EXPECT_EQ(dir.read("out.csv"), kOld);
  EXPECT_THAT(dir.entries(), ElementsAre("out.csv"));
}

TEST(AtomicFileWriter, CommitReplacesAndUnwritableDirectoryThrowsNamingTheFile) {
  ScratchDir dir;
  dir.write("out.csv", kOld);
  write_file_atomically(dir.path() / "out.csv", "new\n");
  EXPECT_EQ(dir.read("out.csv"), "new\n");
  EXPECT_THAT(dir.entries(), ElementsAre("out.csv"));
  try {
    write_file_atomically(dir.path() / "no_such_dir" / "x.csv", "x");
    FAIL() << "expected Error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("no_such_dir/x.csv"));
  }
}

// In a child: open a writer on out.csv, write, then raise `sig`. The handler must remove the
// temporary and let the signal kill the process.
void signal_while_writing(int sig) {
  ScratchDir dir;
  dir.write("out.csv", kOld);
  const pid_t pid = ::fork();
  if (pid == 0) {
    AtomicFileWriter w(dir.path() / "out.csv");
    w.stream() << std::string(1 << 20, 'x');
    w.stream().flush();
    ::raise(sig);
    ::_exit(0);  // not reached: the signal's default action ends the process
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "child exited normally";
  EXPECT_EQ(WTERMSIG(status), sig);
  EXPECT_EQ(dir.read("out.csv"), kOld);
  EXPECT_THAT(dir.entries(), ElementsAre("out.csv"));
}

TEST(AtomicFileWriter, SigintWhileWritingRemovesTheTemporary) { signal_while_writing(SIGINT); }
TEST(AtomicFileWriter, SigtermWhileWritingRemovesTheTemporary) { signal_while_writing(SIGTERM); }

TEST(AtomicFileSet, AllOrNone) {
  ScratchDir dir;
  dir.write("a.csv", kOld);
  dir.write("b.json", kOld);
  AtomicFileSet set;
  set.add(dir.path() / "a.csv", "new a\n");
  set.add(dir.path() / "b.json", "new b\n");
  set.add(dir.path() / "missing_dir" / "c.json", "new c\n");
  EXPECT_THROW(set.commit(), Error);
  EXPECT_EQ(dir.read("a.csv"), kOld);
  EXPECT_EQ(dir.read("b.json"), kOld);
  EXPECT_THAT(dir.entries(), ElementsAre("a.csv", "b.json"));
  AtomicFileSet ok;
  ok.add(dir.path() / "a.csv", "new a\n");
  ok.add(dir.path() / "b.json", "new b\n");
  ok.commit();
  EXPECT_EQ(dir.read("a.csv"), "new a\n");
  EXPECT_EQ(dir.read("b.json"), "new b\n");
}

// ---- the CLI -----------------------------------------------------------------


// Files in the directory other than the ones the test wrote (temporaries, half outputs).
std::vector<std::string> unexpected_entries(const ScratchDir& dir, std::vector<std::string> expected) {
  std::vector<std::string> extra;
  for (const auto& e : dir.entries())
    if (std::find(expected.begin(), expected.end(), e) == expected.end()) extra.push_back(e);
  return extra;
}

TEST(AtomicCliOutput, BadInputFoundAfterStartLeavesPreviousOutput) {
  ScratchDir dir;
  dir.write("g.csv", kUnitCubeGrid);
  // Many good targets, then one outside the grid on the last line.
  std::string targets = "x,y,z\n";
  for (int i = 0; i < 1000; ++i) targets += "0.5,0.5," + std::to_string(i / 1000.0) + "\n";
  dir.write("t.csv", targets + "2,0,0\n");
  dir.write("o.csv", kOld);
  const auto r = testing::run_errfield({"interpolate", "--method", "idw-grid", "--samples", "g.csv", "--targets",
                                        "t.csv", "--coords", "x,y,z", "--value", "v", "--out", "o.csv"},
                                       dir.path());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("t.csv:1002: target (2, 0, 0) is outside the grid"));
  EXPECT_EQ(dir.read("o.csv"), kOld);
  EXPECT_TRUE(unexpected_entries(dir, {"g.csv", "t.csv", "o.csv"}).empty());
}

TEST(AtomicCliOutput, UnwritableOutputIsAnErrorNamingIt) {
  ScratchDir dir;
  dir.write("g.csv", kUnitCubeGrid);
  const auto r = testing::run_errfield(
      {"variogram", "--input", "g.csv", "--coords", "x,y,z", "--value", "v", "--bins", "0:2:1", "--out", "nodir/o.csv"},
      dir.path());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.err, HasSubstr("nodir/o.csv"));
  EXPECT_TRUE(unexpected_entries(dir, {"g.csv"}).empty());
}

TEST(AtomicCliOutput, SimulateWritesAllOutputsOrNone) {
  ScratchDir dir;
  dir.write("o.csv", kOld);
  dir.write("truth.json", kOld);
  auto r = testing::run_errfield({"simulate", "--seed", "3", "--step", "500", "--out", "o.csv", "--truth-out",
                                  "truth.json", "--config-out", "nodir/config.json"},
                                 dir.path());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.err, HasSubstr("nodir/config.json"));
  EXPECT_EQ(dir.read("o.csv"), kOld);
  EXPECT_EQ(dir.read("truth.json"), kOld);
  EXPECT_TRUE(unexpected_entries(dir, {"o.csv", "truth.json"}).empty());
  r = testing::run_errfield({"simulate", "--seed", "3", "--step", "500", "--out", "o.csv", "--truth-out",
                             "truth.json", "--config-out", "config.json"},
                            dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(dir.read("o.csv"), kOld);
  EXPECT_NE(dir.read("truth.json"), kOld);
}

// Random 3-D samples, `n` rows, seeded (simulated data).
// ---- interrupting a job at work -------------------------------------------------------------
//
// A fixed sleep before SIGINT assumes the job is still running then: on a faster machine it may
// have finished, on a loaded one it may not have started. Instead the tests signal once the job
// is at work, judged by the job's own progress (Linux /proc accounting of the child): it has read
// its input files (what follows is computation) and used some CPU time (past start-up).

// rchar (bytes read through read(2) and friends) of `pid`, or -1 when it cannot be read.
long long bytes_read(pid_t pid) {
  std::ifstream io("/proc/" + std::to_string(pid) + "/io");
  for (std::string key; io >> key;) {
    long long v = 0;
    io >> v;
    if (key == "rchar:") return v;
  }
  return -1;
}

// CPU time (user + system) `pid` has used, in ms, or -1 when it cannot be read.
double cpu_ms(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string stat((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto close = stat.rfind(')');  // the command name may hold spaces
  if (close == std::string::npos) return -1;
  std::istringstream rest(stat.substr(close + 2));
  std::string field;
  for (int i = 3; i < 14 && rest >> field; ++i) {
  }
  double utime = 0, stime = 0;
  if (!(rest >> utime >> stime)) return -1;
  return (utime + stime) * 1000.0 / static_cast<double>(::sysconf(_SC_CLK_TCK));
}

bool has_ended(pid_t pid) {
  siginfo_t info{};
  // WNOWAIT: not reaped, wait_errfield still gets its status
  return ::waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOHANG | WNOWAIT) == 0 && info.si_pid != 0;
}

// Waits (polling every 2 ms, at most 20 s) until the job `p` has read `input_bytes` and used
// 50 ms of CPU time, or has ended. On this 2-core machine that is sooner than the fixed 300 ms
// the tests used to sleep; on a faster one it is the same point of the job.
void wait_until_at_work(const testing::CliProcess& p, std::uintmax_t input_bytes) {
  constexpr double kStartupCpuMs = 50.0;
  for (int waited_ms = 0; waited_ms < 20000 && !has_ended(p.pid); waited_ms += 2) {
    const long long read = bytes_read(p.pid);
    if (read >= 0 && static_cast<std::uintmax_t>(read) >= input_bytes && cpu_ms(p.pid) >= kStartupCpuMs) return;
    ::usleep(2000);
  }
}

// Total size of the files in `dir` that `args` name, other than `outputs`: what the job reads.
std::uintmax_t input_bytes(const ScratchDir& dir, const std::vector<std::string>& args,
                           const std::vector<std::string>& outputs) {
  std::uintmax_t total = 0;
  for (const auto& a : args) {
    std::error_code ec;
    if (std::find(outputs.begin(), outputs.end(), a) == outputs.end() &&
        std::filesystem::is_regular_file(dir.path() / a, ec))
      total += std::filesystem::file_size(dir.path() / a);
  }
  return total;
}

std::string random_samples(std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1000.0);
  std::string s = "x,y,z,v\n";
  s.reserve(n * 48);
  for (std::size_t i = 0; i < n; ++i) {
    const double x = u(rng), y = u(rng), z = u(rng);
    s += std::to_string(x) + "," + std::to_string(y) + "," + std::to_string(z) + "," +
         std::to_string(std::sin(x / 200) + 0.001 * y) + "\n";
  }
  return s;
}

TEST(AtomicCliOutput, SigintDuringALongRunLeavesPreviousOutput) {
  ScratchDir dir;
  // 60,000 points: 1.8e9 pairs, seconds of work even on 2 threads; interrupted once it has read
  // them, in the pair loop.
  dir.write("s.csv", random_samples(60000, 1));
  dir.write("o.csv", kOld);
  const std::vector<std::string> args{"variogram", "--input", "s.csv", "--coords", "x,y,z", "--value", "v",
                                      "--bins",    "0:1700:100", "--out", "o.csv"};
  const auto p = testing::start_errfield(args, dir.path());
  wait_until_at_work(p, input_bytes(dir, args, {"o.csv"}));
  ::kill(p.pid, SIGINT);
  const auto r = testing::wait_errfield(p);
  ASSERT_EQ(r.signal, SIGINT) << "finished before the signal (exit " << r.exit_code << "): make the job larger";
  EXPECT_EQ(dir.read("o.csv"), kOld);
  EXPECT_TRUE(unexpected_entries(dir, {"s.csv", "o.csv"}).empty());
}

TEST(AtomicCliOutput, SigintWhileTheOutputIsBeingWrittenRemovesTheTemporary) {
  ScratchDir dir;
  // 300,000 targets in a 2x2x2 grid: a ~15 MB output. inotify reports the temporary file's
  // creation and the test interrupts the process right then, while it writes.
  dir.write("g.csv", kUnitCubeGrid);
  std::string targets = "x,y,z\n";
  for (int i = 0; i < 300000; ++i) {
    const double t = (i % 1000) / 1000.0;
    targets += "0.25,0.5," + std::to_string(t) + "\n";
  }
  dir.write("t.csv", targets);
  dir.write("o.csv", kOld);
  const int fd = ::inotify_init1(IN_NONBLOCK);
  ASSERT_GE(fd, 0);
  ASSERT_GE(::inotify_add_watch(fd, dir.path().c_str(), IN_CREATE), 0);
  const auto p = testing::start_errfield({"interpolate", "--method", "idw-grid", "--samples", "g.csv", "--targets",
                                          "t.csv", "--coords", "x,y,z", "--value", "v", "--out", "o.csv"},
                                         dir.path());
  bool signalled = false;
  alignas(inotify_event) char buf[4096];
  for (int waited_ms = 0; waited_ms < 60000 && !signalled;) {
    pollfd pfd{fd, POLLIN, 0};
    if (::poll(&pfd, 1, 10) <= 0) {
      waited_ms += 10;
      if (has_ended(p.pid)) break;
      continue;
    }
    const ssize_t len = ::read(fd, buf, sizeof buf);
    for (ssize_t off = 0; off < len;) {
      const auto* ev = reinterpret_cast<const inotify_event*>(buf + off);
      if (ev->len && std::string(ev->name).rfind(".o.csv.tmp", 0) == 0) {
        ::kill(p.pid, SIGINT);
        signalled = true;
        break;
      }
      off += static_cast<ssize_t>(sizeof(inotify_event) + ev->len);
    }
  }
  ::close(fd);
  const auto r = testing::wait_errfield(p);
  ASSERT_TRUE(signalled) << "no temporary output file appeared";
  if (r.signal == 0) GTEST_SKIP() << "the output was complete before SIGINT arrived (exit " << r.exit_code << ")";
  EXPECT_EQ(r.signal, SIGINT);
  EXPECT_TRUE(unexpected_entries(dir, {"g.csv", "t.csv", "o.csv"}).empty()) << ::testing::PrintToString(dir.entries());
  const std::string after = dir.read("o.csv");
  if (after != kOld) {
    // On a loaded machine the 15 MB can be written and renamed before this process gets to send
    // the signal, which then ends the tool on its way out. Then o.csv must be the whole new file:
    // never a partial one.
    const auto complete = testing::run_errfield({"interpolate", "--method", "idw-grid", "--samples", "g.csv",
                                                 "--targets", "t.csv", "--coords", "x,y,z", "--value", "v", "--out",
                                                 "complete.csv"},
                                                dir.path());
    ASSERT_EQ(complete.exit_code, 0) << complete.output();
    EXPECT_TRUE(after == dir.read("complete.csv"))
        << "o.csv is neither the previous output nor the complete new one (" << after.size() << " bytes)";
  }
}

// ---- plan, fit, compensate, calibrate, reproduce ------------------------------------------------

// Interrupts `args` once it is at work (wait_until_at_work: its input files read) and checks that
// it died of SIGINT and that the directory holds exactly `expected` afterwards, the files in
// `previous` still with kOld.
void expect_sigint_keeps_previous(const ScratchDir& dir, const std::vector<std::string>& args,
                                  const std::vector<std::string>& expected, const std::vector<std::string>& previous) {
  const auto p = testing::start_errfield(args, dir.path());
  wait_until_at_work(p, input_bytes(dir, args, previous));
  ::kill(p.pid, SIGINT);
  const auto r = testing::wait_errfield(p);
  ASSERT_EQ(r.signal, SIGINT) << testing::command_line(args) << " finished before the signal (exit " << r.exit_code
                              << "): make the job larger\n"
                              << r.err;
  for (const auto& f : previous) EXPECT_EQ(dir.read(f), kOld) << f;
  EXPECT_TRUE(unexpected_entries(dir, expected).empty()) << ::testing::PrintToString(dir.entries());
}

// `errfield simulate` output as the measurement data of fit/calibrate (SIMULATED).
void simulate_into(const ScratchDir& dir, const std::string& step, const std::string& out) {
  const auto r = testing::run_errfield({"simulate", "--seed", "5", "--step", step, "--out", out, "--robot-out",
                                        "robot.json"},
                                       dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
}

const std::vector<std::string> kReproductionFiles{"beyond_orientation.csv", "fig5.csv", "report.html", "table3.csv",
                                                  "table4.csv",        "table6.csv",        "table6_points.csv",
                                                  "table6_spread.csv", "table8.csv"};

TEST(AtomicCliOutput, ReproduceReplacesItsFilesAllOrNone) {
  ScratchDir dir;
  std::filesystem::create_directories(dir.path() / "out" / "report.html");  // cannot be replaced
  for (const auto& f : kReproductionFiles)
    if (f != "report.html") dir.write("out/" + f, kOld);
  auto r = testing::run_errfield({"reproduce", "--runs", "1", "--out", "out"}, dir.path());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.err, HasSubstr("report.html"));
  std::vector<std::string> left;
  for (const auto& e : std::filesystem::directory_iterator(dir.path() / "out")) left.push_back(e.path().filename());
  std::sort(left.begin(), left.end());
  EXPECT_EQ(left, kReproductionFiles) << "no temporary file, no file missing";
  for (const auto& f : kReproductionFiles) {
    if (f != "report.html") {
      EXPECT_EQ(dir.read("out/" + f), kOld) << f << " was replaced although the run failed";
    }
  }
  // An --out directory that cannot be created is an error naming it.
  dir.write("file", "x");
  r = testing::run_errfield({"reproduce", "--runs", "1", "--out", "file/sub"}, dir.path());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.err, HasSubstr("file/sub"));
}

TEST(AtomicCliOutput, SigintDuringReproduceLeavesPreviousFilesAndNoDirectory) {
  ScratchDir dir;
  std::filesystem::create_directories(dir.path() / "out");
  for (const auto& f : kReproductionFiles) dir.write("out/" + f, kOld);
  // --runs 1000 takes minutes; interrupted once both are at work, in the middle of the experiments.
  const auto p = testing::start_errfield({"reproduce", "--runs", "1000", "--out", "out"}, dir.path());
  const auto q = testing::start_errfield({"reproduce", "--runs", "1000", "--out", "fresh"}, dir.path());
  wait_until_at_work(p, 0);
  wait_until_at_work(q, 0);
  ::kill(p.pid, SIGINT);
  ::kill(q.pid, SIGINT);
  const auto r = testing::wait_errfield(p);
  const auto r2 = testing::wait_errfield(q);
  ASSERT_EQ(r.signal, SIGINT) << r.err;
  ASSERT_EQ(r2.signal, SIGINT) << r2.err;
  for (const auto& f : kReproductionFiles) EXPECT_EQ(dir.read("out/" + f), kOld) << f;
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir.path() / "out")) ++n;
  EXPECT_EQ(n, kReproductionFiles.size()) << "a temporary file was left in out/";
  EXPECT_THAT(dir.entries(), ElementsAre("out")) << "the interrupted run into 'fresh' created something";
}

TEST(AtomicCliOutput, PlanWritesOutAndSamplesOutAllOrNone) {
  ScratchDir dir;
  dir.write("p.csv", kOld);
  dir.write("s.csv", kOld);
  const std::vector<std::string> base{"plan", "--cube", "750,-250,350,250", "--step", "125", "--out", "p.csv"};
  auto with = [&](std::vector<std::string> extra) {
    auto a = base;
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  };
  auto r = testing::run_errfield(with({"--samples-out", "nodir/s.csv"}), dir.path());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.err, HasSubstr("nodir/s.csv"));
  EXPECT_EQ(dir.read("p.csv"), kOld) << "--out replaced although --samples-out failed";
  r = testing::run_errfield(with({"--samples-out", "./p.csv"}), dir.path());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.err, HasSubstr("given twice"));
  EXPECT_EQ(dir.read("p.csv"), kOld);
  EXPECT_TRUE(unexpected_entries(dir, {"p.csv", "s.csv"}).empty());
  r = testing::run_errfield(with({"--samples-out", "s.csv"}), dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(dir.read("p.csv"), kOld);
  EXPECT_NE(dir.read("s.csv"), kOld);
}

TEST(AtomicCliOutput, SigintDuringPlanLeavesPreviousOutputs) {
  ScratchDir dir;
  dir.write("p.csv", kOld);
  dir.write("s.csv", kOld);
  // 132,651 grid points and 125,000 samples, one IK each: about 1.5 s.
  expect_sigint_keeps_previous(dir,
                               {"plan", "--cube", "750,-250,350,250", "--step", "5", "--samples-out", "s.csv", "--out",
                                "p.csv"},
                               {"p.csv", "s.csv"}, {"p.csv", "s.csv"});
}

TEST(AtomicCliOutput, FitFailureAndSigintLeavePreviousModel) {
  ScratchDir dir;
  // 4,913 grid points: a kriging fit takes seconds (distance-idw with its one-pass leave-one-out
  // now takes a fraction of one, too little to be interrupted at work)
  simulate_into(dir, "31.25", "g.csv");
  const auto r0 = testing::run_errfield({"simulate", "--seed", "5", "--step", "125", "--measure", "distances", "--out",
                                         "d.csv"},
                                        dir.path());
  ASSERT_EQ(r0.exit_code, 0) << r0.err;
  dir.write("m.json", kOld);
  const auto r = testing::run_errfield({"fit", "--robot", "robot.json", "--data", "d.csv", "--method", "position-idw",
                                        "--out", "m.json"},
                                       dir.path());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("mx"));
  EXPECT_EQ(dir.read("m.json"), kOld);
  expect_sigint_keeps_previous(
      dir, {"fit", "--robot", "robot.json", "--data", "g.csv", "--method", "distance-kriging", "--out", "m.json"},
      {"g.csv", "d.csv", "robot.json", "m.json"}, {"m.json"});
}

// The plan of the paper cube (125 grid points with joints, for the robot.json of simulate_into)
// as compensation targets, `copies` times.
std::string plan_targets(const ScratchDir& dir, int copies) {
  const auto r = testing::run_errfield(
      {"plan", "--robot", "robot.json", "--cube", "750,-250,350,500", "--step", "125", "--out", "plan.csv"}, dir.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const std::string plan = dir.read("plan.csv");
  const std::size_t header_end = plan.find('\n') + 1;
  std::string out = plan.substr(0, header_end);
  for (int i = 0; i < copies; ++i) out += plan.substr(header_end);
  std::filesystem::remove(dir.path() / "plan.csv");
  return out;
}

TEST(AtomicCliOutput, CompensateFailureAndSigintLeavePreviousOutput) {
  ScratchDir dir;
  simulate_into(dir, "125", "g.csv");
  ASSERT_EQ(testing::run_errfield({"fit", "--robot", "robot.json", "--data", "g.csv", "--method", "position-idw",
                                   "--out", "m.json"},
                                  dir.path())
                .exit_code,
            0);
  // A bad cell on the last of 126 rows: found after the work started.
  dir.write("bad.csv", plan_targets(dir, 1) + "g125,grid,750,-250,350,180,0,0,abc,0,0,0,0,0\n");
  dir.write("j.csv", kOld);
  const auto r = testing::run_errfield({"compensate", "--robot", "robot.json", "--model", "m.json", "--targets",
                                        "bad.csv", "--out", "j.csv"},
                                       dir.path());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("bad.csv"), HasSubstr("q1")));
  EXPECT_EQ(dir.read("j.csv"), kOld);
  // 200,000 targets: seconds of work.
  dir.write("t.csv", plan_targets(dir, 1600));
  expect_sigint_keeps_previous(
      dir, {"compensate", "--robot", "robot.json", "--model", "m.json", "--targets", "t.csv", "--out", "j.csv"},
      {"g.csv", "robot.json", "m.json", "bad.csv", "t.csv", "j.csv"}, {"j.csv"});
}

TEST(AtomicCliOutput, CalibrateWritesOutAndReportAllOrNone) {
  ScratchDir dir;
  simulate_into(dir, "125", "g.csv");
  dir.write("cal.json", kOld);
  dir.write("cal.txt", kOld);
  auto r = testing::run_errfield({"calibrate", "--robot", "robot.json", "--data", "g.csv", "--out", "cal.json", "--report", "nodir/cal.txt"},
                                 dir.path());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.err, HasSubstr("nodir/cal.txt"));
  EXPECT_EQ(dir.read("cal.json"), kOld) << "the model was replaced although the report could not be written";
  EXPECT_TRUE(unexpected_entries(dir, {"g.csv", "robot.json", "cal.json", "cal.txt"}).empty());
  r = testing::run_errfield({"calibrate", "--robot", "robot.json", "--data", "g.csv", "--out", "cal.json", "--report", "cal.txt"},
                            dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(dir.read("cal.json"), kOld);
  EXPECT_NE(dir.read("cal.txt"), kOld);
}

TEST(AtomicCliOutput, SigintDuringCalibrateLeavesPreviousOutputs) {
  ScratchDir dir;
  simulate_into(dir, "25", "g.csv");  // 9,262 measurements: seconds of Levenberg-Marquardt
  dir.write("cal.json", kOld);
  dir.write("cal.txt", kOld);
  expect_sigint_keeps_previous(dir, {"calibrate", "--robot", "robot.json", "--data", "g.csv", "--out", "cal.json", "--report", "cal.txt"},
                               {"g.csv", "robot.json", "cal.json", "cal.txt"}, {"cal.json", "cal.txt"});
}

}  // namespace
}  // namespace errfield
