// Atomic outputs, round two (issue 12): what an output name can be. The same file named twice in
// a different spelling (`c.json` and `./c.json`, a symlink to it); a symlink (followed: the file
// it names is replaced, the link stays); a FIFO or a character device (written through, never
// replaced by a regular file); a long but valid name (the temporary's name stays within
// NAME_MAX); every signal that ends the process while a file is being written (no temporary left).
//
// Never `--out /dev/null` itself here: the tests run as root in CI, and the code before these
// fixes renamed a regular file over the target, i.e. over the machine's /dev/null. A symlink in
// the scratch directory pointing at /dev/null shows the same defect (the link was replaced)
// without that risk.

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "errfield/atomic_file.hpp"
#include "errfield/error.hpp"
#include "support/cli_test_common.hpp"

namespace errfield {
namespace output_targets_test {

using namespace testing::cli_common;
using ::testing::ElementsAre;
namespace fs = std::filesystem;

constexpr const char* kOld = "previous output\n";

// `errfield variogram` on the unit-cube grid, writing `out` (relative to the scratch directory).
std::vector<std::string> variogram_to(const std::string& out) {
  return {"variogram", "--input", "g.csv", "--coords", "x,y,z", "--value", "v", "--bins", "0:2:0.5", "--out", out};
}

// ---- the same file given twice ---------------------------------------------------------------

TEST(OutputNames, SameNewFileInTwoSpellingsIsRefusedInTheLibrary) {
  ScratchDir dir;
  const fs::path a = dir.path() / "c.json";
  const fs::path b = dir.path() / "." / "sub" / ".." / "c.json";
  fs::create_directory(dir.path() / "sub");
  EXPECT_TRUE(same_output_file(a, b));
  AtomicFileSet set;
  set.add(a, "model\n");
  set.add(b, "report\n");
  EXPECT_THROW(set.commit(), ArgumentError);
  EXPECT_THAT(dir.entries(), ElementsAre("sub")) << "nothing may be written";
  // Not the same: another name, and two writes to one device.
  EXPECT_FALSE(same_output_file(a, dir.path() / "d.json"));
  EXPECT_FALSE(same_output_file("/dev/null", "/dev/null"));
}

TEST(OutputNames, CalibrateOutAndReportAsOneFileAreRefused) {
  ScratchDir dir;
  ASSERT_EQ(run_errfield({"simulate", "--seed", "5", "--step", "250", "--out", "g.csv"}, dir.path()).exit_code, 0);
  // c.json does not exist yet: the check compared strings and let the report overwrite the model.
  auto r = run_errfield({"calibrate", "--data", "g.csv", "--out", "c.json", "--report", "./c.json"}, dir.path());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, AllOf(HasSubstr("given twice"), HasSubstr("c.json")));
  EXPECT_FALSE(fs::exists(dir.path() / "c.json"));
  // A symlink to the model is the same file too.
  fs::create_symlink("c.json", dir.path() / "report-link.txt");
  r = run_errfield({"calibrate", "--data", "g.csv", "--out", "c.json", "--report", "report-link.txt"}, dir.path());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("given twice"));
  EXPECT_FALSE(fs::exists(dir.path() / "c.json"));
}

TEST(OutputNames, SimulateAndPlanSecondOutputsAsTheFirstAreRefused) {
  ScratchDir dir;
  auto r = run_errfield({"simulate", "--seed", "5", "--step", "250", "--out", "o.csv", "--truth-out", "./o.csv"},
                        dir.path());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("given twice"));
  EXPECT_FALSE(fs::exists(dir.path() / "o.csv"));
  fs::create_directory(dir.path() / "d");
  r = run_errfield({"plan", "--cube", "750,-250,350,250", "--step", "125", "--out", "p.csv", "--samples-out",
                    "d/../p.csv"},
                   dir.path());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("given twice"));
  EXPECT_FALSE(fs::exists(dir.path() / "p.csv"));
}

// ---- symlinks, FIFOs, devices ----------------------------------------------------------------

TEST(OutputNames, ASymlinkIsFollowedAndStaysALink) {
  ScratchDir dir;
  dir.write("g.csv", kUnitCubeGrid);
  fs::create_directory(dir.path() / "real");
  dir.write("real/v.csv", kOld);
  fs::create_symlink("real/v.csv", dir.path() / "link.csv");
  auto r = run_errfield(variogram_to("link.csv"), dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(dir.path() / "link.csv")) << "the link was replaced by a regular file";
  EXPECT_THAT(dir.read("real/v.csv"), HasSubstr("lag_lo,lag_hi"));
  // A dangling link: the file it names is created.
  fs::create_symlink("real/new.csv", dir.path() / "dangling.csv");
  r = run_errfield(variogram_to("dangling.csv"), dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(dir.path() / "dangling.csv"));
  EXPECT_THAT(dir.read("real/new.csv"), HasSubstr("lag_lo,lag_hi"));
  EXPECT_THAT(dir.entries(), ElementsAre("dangling.csv", "g.csv", "link.csv", "real"));
}

TEST(OutputNames, ALinkToACharacterDeviceIsWrittenThroughNotReplaced) {
  ScratchDir dir;
  dir.write("g.csv", kUnitCubeGrid);
  fs::create_symlink("/dev/null", dir.path() / "sink");
  // One output (variogram) and a set of outputs (calibrate --out/--report) into the device.
  auto r = run_errfield(variogram_to("sink"), dir.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(dir.path() / "sink")) << "replaced by a regular file";
  ASSERT_EQ(
      run_errfield({"simulate", "--seed", "5", "--step", "250", "--out", "s.csv", "--robot-out", "r.json"}, dir.path())
          .exit_code,
      0);
  r = run_errfield({"calibrate", "--robot", "r.json", "--data", "s.csv", "--out", "c.json", "--report", "sink"},
                   dir.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(dir.path() / "sink"));
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  EXPECT_THAT(dir.entries(), ElementsAre("c.json", "g.csv", "r.json", "s.csv", "sink"));
}

TEST(OutputNames, AFifoIsWrittenThroughNotReplaced) {
  ScratchDir dir;
  dir.write("g.csv", kUnitCubeGrid);
  const fs::path fifo = dir.path() / "pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // Open the reading end first (non-blocking) so that the tool's open for writing does not wait.
  const int fd = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(fd, 0);
  const auto p = testing::start_errfield(variogram_to("pipe"), dir.path());
  std::string received;
  char buf[4096];
  bool ended = false;
  for (int waited_ms = 0; waited_ms < 20000; waited_ms += 10) {
    pollfd pfd{fd, POLLIN, 0};
    if (::poll(&pfd, 1, 10) > 0)
      for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;) received.append(buf, static_cast<std::size_t>(n));
    siginfo_t info{};
    if (!ended && ::waitid(P_PID, static_cast<id_t>(p.pid), &info, WEXITED | WNOHANG | WNOWAIT) == 0 &&
        info.si_pid != 0)
      ended = true;
    else if (ended)
      break;  // one more read after the end
  }
  for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;) received.append(buf, static_cast<std::size_t>(n));
  ::close(fd);
  const auto r = testing::wait_errfield(p);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  struct stat st {};
  ASSERT_EQ(::lstat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode)) << "the FIFO was replaced by a regular file";
  EXPECT_THAT(received, HasSubstr("lag_lo,lag_hi"));
  EXPECT_THAT(dir.entries(), ElementsAre("g.csv", "pipe"));
}

// Issue 47 item 10: `variogram --plot /dev/full --out v.csv` replaced v.csv, then exited 1: the
// set wrote its device targets after renaming the regular ones. A device that cannot be written
// now leaves every regular file of the set as it was (all or none), in the library and in each
// command with a --plot beside its --out. (A link to /dev/full: never a target under /dev itself.)
TEST(OutputNames, AFullDeviceInASetLeavesTheOtherFilesUntouched) {
  ScratchDir dir;
  fs::create_symlink("/dev/full", dir.path() / "full");
  dir.write("a.csv", kOld);
  AtomicFileSet set;
  set.add(dir.path() / "a.csv", "new\n");
  set.add(dir.path() / "full", "picture\n");
  EXPECT_THROW(set.commit(), Error);
  EXPECT_EQ(dir.read("a.csv"), kOld);
  EXPECT_THAT(dir.entries(), ElementsAre("a.csv", "full")) << "no temporary left";

  dir.write("g.csv", kUnitCubeGrid);
  dir.write("v.csv", kOld);
  auto args = variogram_to("v.csv");
  args.insert(args.end(), {"--plot", "full"});
  auto r = run_errfield(args, dir.path());
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(dir.read("v.csv"), kOld) << "variogram replaced --out although --plot failed";

  dir.write("e.csv", "lag_lo,lag_hi,lag_mean,gamma,pairs\n0,1,0.5,0.1,30\n1,2,1.5,0.2,40\n2,3,2.5,0.3,50\n3,4,3.5,0.32,50\n");
  dir.write("m.json", kOld);
  r = run_errfield({"fit-variogram", "--input", "e.csv", "--model", "sph", "--out", "m.json", "--plot", "full"}, dir.path());
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(dir.read("m.json"), kOld) << "fit-variogram replaced --out although --plot failed";

  // Without --out the table goes to standard output: a full one leaves the picture as it was.
  dir.write("p.svg", kOld);
  args = variogram_to("v.csv");
  args.resize(args.size() - 2);
  args.insert(args.end(), {"--plot", "p.svg"});
  r = testing::run_errfield_to_full_stdout(args, dir.path());
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(dir.read("p.svg"), kOld) << "variogram replaced --plot although standard output failed";
  // cv wrote --out, then its summary to standard output.
  dir.write("o.csv", kOld);
  r = testing::run_errfield_to_full_stdout(
      {"cv", "--method", "idw", "--samples", "g.csv", "--coords", "x,y,z", "--value", "v", "--out", "o.csv"}, dir.path());
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(dir.read("o.csv"), kOld) << "cv replaced --out although standard output failed";
}

TEST(OutputNames, ADirectoryOrALinkToOneIsRefused) {
  ScratchDir dir;
  fs::create_directory(dir.path() / "d");
  fs::create_directory_symlink("d", dir.path() / "dlink");
  EXPECT_THROW(write_file_atomically(dir.path() / "d", "x"), Error);
  EXPECT_THROW(write_file_atomically(dir.path() / "dlink", "x"), Error);
  EXPECT_TRUE(fs::is_directory(dir.path() / "d"));
  EXPECT_TRUE(fs::is_symlink(dir.path() / "dlink"));
}

// ---- long names --------------------------------------------------------------------------------

TEST(OutputNames, ALongValidNameWorks) {
  ScratchDir dir;
  for (const std::size_t length : {250u, 255u}) {
    const std::string name = std::string(length - 4, 'n') + ".csv";
    write_file_atomically(dir.path() / name, "x\n");
    EXPECT_EQ(dir.read(name), "x\n") << length;
    fs::remove(dir.path() / name);
  }
  // Multi-byte UTF-8 names are shortened at a character boundary.
  std::string utf8;
  while (utf8.size() + 2 <= 250) utf8 += "\xc3\xa9";  // é
  write_file_atomically(dir.path() / utf8, "y\n");
  EXPECT_EQ(dir.read(utf8), "y\n");
  fs::remove(dir.path() / utf8);
  dir.write("g.csv", kUnitCubeGrid);
  const std::string name = std::string(246, 'v') + ".csv";
  const auto r = run_errfield(variogram_to(name), dir.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(dir.read(name), HasSubstr("lag_lo"));
  EXPECT_THAT(dir.entries(), ElementsAre("g.csv", name));
}

// ---- signals while writing ----------------------------------------------------------------------

// In a child: open a writer on out.csv, write, then raise `sig` (set up as a user's shell would:
// default action, core dumps off). The temporary must be gone and the signal must end the child.
void signal_while_writing(int sig) {
  ScratchDir dir;
  dir.write("out.csv", kOld);
  const pid_t pid = ::fork();
  if (pid == 0) {
    const rlimit no_core{0, 0};
    ::setrlimit(RLIMIT_CORE, &no_core);
    AtomicFileWriter w(dir.path() / "out.csv");
    w.stream() << std::string(1 << 20, 'x');
    w.stream().flush();
    ::raise(sig);
    ::_exit(0);  // not reached: the signal's default action ends the process
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "child exited normally with " << WEXITSTATUS(status);
  EXPECT_EQ(WTERMSIG(status), sig);
  EXPECT_EQ(dir.read("out.csv"), kOld);
  EXPECT_THAT(dir.entries(), ElementsAre("out.csv")) << strsignal(sig);
}

class SignalWhileWriting : public ::testing::TestWithParam<int> {};

TEST_P(SignalWhileWriting, RemovesTheTemporary) { signal_while_writing(GetParam()); }

INSTANTIATE_TEST_SUITE_P(EndingSignals, SignalWhileWriting,
                         ::testing::Values(SIGHUP, SIGQUIT, SIGPIPE, SIGUSR1, SIGUSR2, SIGALRM, SIGABRT),
                         [](const auto& info) { return std::string(sigabbrev_np(info.param)); });

TEST(SignalWhileWriting, AnIgnoredSignalStaysIgnored) {
  // nohup: SIGHUP ignored before the first writer. The write must go on and complete.
  ScratchDir dir;
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::signal(SIGHUP, SIG_IGN);
    AtomicFileWriter w(dir.path() / "out.csv");
    w.stream() << "complete\n";
    ::raise(SIGHUP);
    w.commit();
    ::_exit(0);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_EQ(dir.read("out.csv"), "complete\n");
}

// The CLI at a file-size limit: the kernel sends SIGXFSZ in the middle of writing the temporary,
// deterministically. The previous output stays and no temporary is left.
TEST(SignalWhileWriting, FileSizeLimitDuringTheCliWriteLeavesNoTemporary) {
  ScratchDir dir;
  dir.write("g.csv", kUnitCubeGrid);
  std::string targets = "x,y,z\n";
  for (int i = 0; i < 2000; ++i) targets += "0.25,0.5," + std::to_string((i % 1000) / 1000.0) + "\n";
  dir.write("t.csv", targets);
  dir.write("o.csv", kOld);
  const fs::path err = dir.path().string() + ".stderr";
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (::chdir(dir.path().c_str()) != 0) ::_exit(127);
    const int e = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(e, 2);
    const rlimit no_core{0, 0};
    ::setrlimit(RLIMIT_CORE, &no_core);
    const rlimit small{16384, 16384};  // the output is ~60 KB
    ::setrlimit(RLIMIT_FSIZE, &small);
    const char* argv[] = {ERRFIELD_CLI_PATH, "interpolate", "--method", "idw-grid", "--samples", "g.csv",
                          "--targets", "t.csv", "--coords", "x,y,z", "--value", "v", "--out", "o.csv", nullptr};
    ::execv(ERRFIELD_CLI_PATH, const_cast<char**>(argv));
    ::_exit(127);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  const std::string stderr_text = ScratchDir::slurp(err);
  fs::remove(err);
  ASSERT_TRUE(WIFSIGNALED(status)) << "exit " << WEXITSTATUS(status) << ": " << stderr_text;
  EXPECT_EQ(WTERMSIG(status), SIGXFSZ);
  EXPECT_EQ(dir.read("o.csv"), kOld);
  EXPECT_THAT(dir.entries(), ElementsAre("g.csv", "o.csv", "t.csv"));
}

}  // namespace
}  // namespace errfield
