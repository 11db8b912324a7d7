// bench_clearance [--repeat N] [--limit S] --tau T FILE:
// minimum clearance within one mesh, ours alone (no peer library offers it:
// CGAL has none, Blender's "minimum thickness" is a stub). Prints one JSON
// object: the timed methods, and the outcome of one untimed run (distances,
// pairs, displacements).
//
// Ours: enforceClearance, within the layer, rounded to float (the filter's
// configuration); also measureClearance alone, the detection it repeats.
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "benchmarks/harness.h"
#include "common/io/mesh_io.h"
#include "common/repair/clearance/clearance.h"

using namespace meshmend;
using namespace meshmend::bench;

int main(int argc, char** argv) {
  CommandLine args(argc, argv);
  const int repeat = args.integer("--repeat", 3), limit = args.integer("--limit", 600);
  const double tau = args.real("--tau", 0);
  if (!args.complete(1, 1, "bench_clearance [--repeat N] [--limit SECONDS] --tau T FILE")) return 1;
  if (!(tau > 0)) {
    std::fprintf(stderr, "bench_clearance: --tau must be more than 0\n");
    return 1;
  }
  const std::string file = args.files()[0];
  ClearanceOptions enforce;
  enforce.tau = tau;
  enforce.scope = ClearanceScope::kWithinLayers;
  enforce.round_to_float = true;
  ClearanceMeasureOptions measureOptions;
  measureOptions.tau = tau;
  measureOptions.scope = ClearanceScope::kWithinLayers;

  std::vector<Method> methods;
  methods.push_back({"meshmend_enforce_clearance", "ours", [=] {
                       auto input = std::make_shared<Mesh>(readMesh(file));
                       return std::function<long()>([=] {
                         Mesh copy(*input);  // enforcing works in place
                         std::vector<Mesh*> layers{&copy};
                         return long(enforceClearance(layers, enforce).violating_pairs_after);
                       });
                     }});
  methods.push_back(
      {"meshmend_measure_clearance", "alternative", [=] {
         auto input = std::make_shared<Mesh>(readMesh(file));
         return std::function<long()>(
             [=] { return long(measureClearance({input.get()}, measureOptions).violating_pairs); });
       }});
  std::vector<JsonObject> results;
  for (const Method& m : methods) {
    const Measurement r = measure(m, repeat, limit);
    results.push_back(toJson(r));
    std::fprintf(stderr, "  %-28s %s\n", m.name.c_str(), toJson(r).str().c_str());
  }
  // The outcome, untimed: what the enforcement reached.
  Mesh mesh = readMesh(file);
  std::vector<Mesh*> layers{&mesh};
  const ClearanceResult outcome = enforceClearance(layers, enforce);
  JsonObject out;
  out.set("file", file)
      .set("faces", std::size_t(mesh.fn))
      .set("tau", tau)
      .set("repeat", repeat)
      .set("methods", results)
      .set("outcome", toJson(outcome));
  std::printf("%s\n", out.str(true).c_str());
}
