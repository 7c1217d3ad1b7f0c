// SPDX-License-Identifier: MIT
// make_simulation (sim.h): the engine chosen by name.
#include "sim.h"
#include "boxtree/error.h"

namespace demo {

std::unique_ptr<Simulation> make_simulation(const std::string& engine, const Scene& scene, const SimOptions& options) {
  if (engine == "bullet") return make_bullet_simulation(scene, options);
  if (engine == "ode") return make_ode_simulation(scene, options);
  throw boxtree::Error("unknown engine '" + engine + "' (bullet or ode)");
}

}  // namespace demo
