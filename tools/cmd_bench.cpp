// quadrix bench …: benchmarks that write CSV/JSON (and plots) of run time against error.
// Each benchmark lives in its own file and registers under the `bench` group.
#include "tools/cli.h"

namespace quadrix::cli {

void add_bench_render(CLI::App& bench, Commands& commands);
void add_bench_fit(CLI::App& bench, Commands& commands);
void add_bench_implicit(CLI::App& bench, Commands& commands);

void add_bench(CLI::App& root, Commands& commands) {
  auto* bench = root.add_subcommand("bench", "Benchmarks: run time against error, side by side with baselines");
  bench->require_subcommand(1);
  add_bench_render(*bench, commands);
  add_bench_fit(*bench, commands);
  add_bench_implicit(*bench, commands);
}

}  // namespace quadrix::cli
