// `errfield reproduce`: the paper's experiments on the built-in simulated robot and tracker.
#include <chrono>
#include <filesystem>
#include <iostream>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "errfield/error.hpp"
#include "errfield/reproduction/paper_reproduction.hpp"

namespace errfield::cli {
namespace {

void add_reproduce_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "reproduce",
      "Run the paper's experiments (Tables 3, 4, 6, 8 and Fig. 5) on the built-in SIMULATED ER20-C10 and laser\n"
      "tracker; print the tables beside the paper's values and write CSVs and report.html. Beyond the paper:\n"
      "compensation with varying tool orientation, task vs joint space (beyond_orientation.csv).\n"
      "Example: errfield reproduce --out errfield-out --seed 1 --runs 20");
  struct Args {
    std::string out = "errfield-out";
    std::uint64_t seed = 1;
    int runs = 20;
    int threads = 0;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("--out", args->out, "output directory (created if missing)")->capture_default_str();
  cmd->add_option("--seed", args->seed, "master seed; the same seed gives the same numbers")
      ->check(kUnsignedInteger)
      ->capture_default_str();
  cmd->add_option("--runs", args->runs, "repetitions of Table 6 (>= 1): each draws new samples, measurement noise and repeatability on the same "
                  "simulated robot and refits every method")->capture_default_str();
  cmd->add_option("--threads", args->threads, "OpenMP threads (0 = default)")->capture_default_str();
  cmd->callback([args] {
    reproduction::ReproductionOptions options;
    options.seed = args->seed;
    options.runs = args->runs;
    options.threads = args->threads;
    check_thread_count("--threads", args->threads);  // naming the option, before validate() does
    options.validate();
    // Each run is new samples and measurements of the same simulated robot and six fitted methods
    // (a few ms and a few MB while it lasts); 2e9 runs exhausted the memory before the first finished.
    constexpr int kMaxRuns = 10000;
    if (args->runs > kMaxRuns)
      throw ResourceError("--runs " + std::to_string(args->runs) + ": at most " + std::to_string(kMaxRuns) +
                          " runs per job (each simulates the measurements and refits every method; the paper uses 20); "
                          "use a smaller --runs");
    // Options first, then an --out that can never become a directory: both fail now, not after
    // minutes of work. (Nothing is created yet: an interrupted run leaves no empty directory.)
    for (std::filesystem::path p = std::filesystem::absolute(args->out); !p.empty(); p = p.parent_path()) {
      std::error_code ec;
      const auto st = std::filesystem::status(p, ec);
      if (std::filesystem::exists(st)) {
        if (!std::filesystem::is_directory(st))
          throw ArgumentError("--out '" + args->out + "': '" + p.string() + "' exists and is not a directory");
        break;
      }
      if (p == p.parent_path()) break;
    }
    std::unique_ptr<Progress> progress;
    std::string stage;
    options.progress = [&](std::string_view s, std::size_t done, std::size_t total) {
      if (s != stage) {
        if (progress) progress->finish();
        stage = std::string(s);
        progress = std::make_unique<Progress>(stage, total);
      }
      progress->update(done);
    };
    const auto result = reproduction::reproduce_paper(options);
    if (progress) progress->finish();
    std::cout << reproduction::reproduction_summary(result);
    require_standard_output();  // before the files: a run that fails leaves the previous ones
    const auto files = reproduction::write_reproduction(result, args->out);
    std::cout << "\nwritten (SIMULATED data):\n";
    for (const auto& f : files) std::cout << "  " << f.string() << "\n";
  });
}

Registration register_reproduce{"reproduce", 90, &add_reproduce_command};

}  // namespace
}  // namespace errfield::cli
