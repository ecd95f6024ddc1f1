// quadrix synth KIND -o FILE: small analytic models for tests and the demo.
#include <fmt/format.h>

#include "core/log.h"
#include "core/model_io.h"
#include "core/synth.h"
#include "tools/cli.h"

namespace quadrix::cli {

void add_synth(CLI::App& root, Commands& commands) {
  auto* app = root.add_subcommand("synth", "Write a small analytic model");
  struct Args {
    std::string kind, out;
    SynthOptions options;
  };
  auto a = std::make_shared<Args>();
  app->add_option("KIND", a->kind, "Model kind")->required()->check(CLI::IsMember(synth_kinds()));
  app->add_option("-o,--out", a->out, "Output .qxm file")->required();
  app->add_option("--count", a->options.count, "Primitives (glyphs, slim-sphere)")->check(CLI::Range(0, 50'000'000));
  app->add_option("--resolution", a->options.resolution, "Grid cells per axis (hyperboloids)")->check(CLI::Range(0, 512));
  app->add_option("--seed", a->options.seed, "Random seed (glyphs)");
  commands.push_back({app, [a](const CommonOptions&, Report& report) {
                        Model m = synth_model(a->kind, a->options);
                        write_model(m, a->out);
                        report.json["synth"] = {{"kind", a->kind},     {"out", a->out},
                                                {"slim", m.slims.size()}, {"tet", m.tets.size()},
                                                {"glyph", m.glyphs.size()}};
                        log::info("wrote {} ({} primitives)", a->out, m.size());
                        return kOk;
                      }});
}

}  // namespace quadrix::cli
