// `fremenctl model`: one state's FreMEn model — spectrum components, the published model P, the
// per-order prediction errors, persistence — and, with --plot, a picture of p(t) over a week with
// the observations (as the paper's Figs. 1-2), as SVG or PNG.
#pragma once

#include "CLI/CLI.hpp"

namespace fremen::client {

void RegisterModelCommand(CLI::App& app);

}  // namespace fremen::client
