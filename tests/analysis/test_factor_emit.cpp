// The fitted table as code (analysis/factor_emit.h): the emitted C, compiled
// by the system's C compiler, returns what the `fitted` method's factor
// returns (terminator_factor, the function the evaluator calls) to
// rounding; the GLSL compiles with glslang (Khronos' reference compiler).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/factor_emit.h"
#include "core/terminator.h"
#include "temp_dir_test.h"

namespace penumbra {
namespace {

// A table with values in [0, 2] drawn from a fixed seed.
std::shared_ptr<FactorTable> random_table(const FactorGrid& grid, unsigned seed) {
  auto table = std::make_shared<FactorTable>();
  table->grid = grid;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> value(0.0, 2.0);
  table->values.resize(std::size_t(grid.cells()));
  for (double& v : table->values) v = value(rng);
  return table;
}

Vec3 random_unit(std::mt19937& rng) {
  std::normal_distribution<double> n;
  return normalize(Vec3{n(rng), n(rng), n(rng)});
}

struct Point {
  Vec3 ng, ns, wi, wo;
};

// Points over the whole sphere of directions, and some with Ns near Ng so
// that the deviation axis's first cells are reached.
std::vector<Point> random_points(int count) {
  std::mt19937 rng(7);
  std::vector<Point> points;
  for (int i = 0; i < count; ++i) {
    Point p{{0, 0, 1}, random_unit(rng), random_unit(rng), random_unit(rng)};
    if (i % 2) p.ns = normalize(p.ng + 0.6 * p.ns);
    points.push_back(p);
  }
  return points;
}

double cosine(const Point& p, FactorInput input) {
  switch (input) {
    case FactorInput::kLight:
      return dot(p.ng, p.wi);
    case FactorInput::kDeviation:
      return dot(p.ng, p.ns);
    case FactorInput::kShading:
      return dot(p.ns, p.wi);
    case FactorInput::kView:
      return dot(p.ng, p.wo);
  }
  return 0.0;
}

std::string run(const std::string& command) {
  std::string out;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return out;
  char buffer[4096];
  while (std::fgets(buffer, sizeof buffer, pipe)) out += buffer;
  pclose(pipe);
  return out;
}

class Emit : public TempDirTest {};

// The grid of penumbra fit's default (light, deviation) and a grid of three
// axes given out of argument order, so the arguments' reordering and the
// general corner loop are both exercised.
TEST_F(Emit, CompiledCMatchesTheFittedMethodToRounding) {
  const std::vector<FactorGrid> grids = {
      {{{FactorInput::kLight, 20.0, 120.0, 2.0}, {FactorInput::kDeviation, 0.0, 60.0, 4.0}}},
      {{{FactorInput::kShading, 0.0, 180.0, 15.0},
        {FactorInput::kLight, 30.0, 150.0, 10.0},
        {FactorInput::kDeviation, 0.0, 45.0, 9.0}}}};
  const std::vector<Point> points = random_points(4000);
  for (std::size_t g = 0; g < grids.size(); ++g) {
    const auto table = random_table(grids[g], 11 + unsigned(g));
    std::ofstream(path("fitted.c")) << emit_factor_table(*table, EmitLanguage::kC, "test table");
    // The arguments in the emitted order: light, deviation, shading, view.
    std::vector<FactorInput> inputs;
    for (const FactorAxis& a : table->grid.axes) inputs.push_back(a.input);
    std::sort(inputs.begin(), inputs.end());
    std::string args;
    for (std::size_t k = 0; k < inputs.size(); ++k)
      args += (k ? ", c[" : "c[") + std::to_string(k) + "]";
    std::ofstream(path("main.c"))
        << "#include <stdio.h>\n#include \"fitted.c\"\nint main(void) {\n  double c[4];\n"
        << "  while (scanf(\"%lf %lf %lf %lf\", &c[0], &c[1], &c[2], &c[3]) == 4)\n"
        << "    printf(\"%.17g\\n\", penumbra_fitted_g(" << args << "));\n  return 0;\n}\n";
    const std::string exe = path("fitted");
    ASSERT_EQ(std::system(("cc -std=c99 -O2 -Wall -Werror -o " + exe + " " + path("main.c") +
                           " -lm 2>" + path("cc.log"))
                              .c_str()),
              0)
        << std::ifstream(path("cc.log")).rdbuf();
    std::ofstream in(path("points.txt"));
    for (const Point& p : points) {
      char line[200];
      std::snprintf(line, sizeof line, "%.17g %.17g %.17g %.17g\n", cosine(p, inputs[0]),
                    cosine(p, inputs[1]), inputs.size() > 2 ? cosine(p, inputs[2]) : 0.0, 0.0);
      in << line;
    }
    in.close();
    std::istringstream out(run(exe + " < " + path("points.txt")));
    MethodSettings fitted{TerminatorMethod::kFitted, 0.0, table, nullptr, {}};
    int inside = 0;
    for (const Point& p : points) {
      double emitted = -1.0;
      ASSERT_TRUE(out >> emitted);
      const double expected = terminator_factor(fitted, p.ng, p.ns, p.wi, p.wo);
      EXPECT_NEAR(emitted, expected, 1e-12) << "grid " << g;
      inside += expected != 1.0;
    }
    EXPECT_GT(inside, 1000) << "too few points inside grid " << g;
  }
}

TEST_F(Emit, GlslCompilesWithTheReferenceCompiler) {
  if (std::system("command -v glslangValidator >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "glslangValidator (Debian package glslang-tools) is not installed";
  const FactorGrid grid{
      {{FactorInput::kLight, 20.0, 120.0, 2.0}, {FactorInput::kDeviation, 0.0, 60.0, 4.0}}};
  std::ofstream(path("fitted.frag"))
      << "#version 330 core\n"
      << emit_factor_table(*random_table(grid, 3), EmitLanguage::kGlsl, "test table")
      << "out vec4 colour;\nvoid main() { colour = vec4(penumbra_fitted_g(0.3, 0.95)); }\n";
  const std::string log = run("glslangValidator " + path("fitted.frag") + " 2>&1; echo rc=$?");
  EXPECT_NE(log.find("rc=0"), std::string::npos) << log;
}

// Text from a provenance line cannot end the comment it goes into.
TEST_F(Emit, ProvenanceCannotLeaveTheComment) {
  const FactorGrid grid{{{FactorInput::kLight, 0.0, 90.0, 45.0}}};
  FactorTable table{grid, {0.5, 1.0}};
  const std::string code = emit_factor_table(table, EmitLanguage::kC, "x */ int evil; /*\n");
  EXPECT_EQ(code.find("*/ int evil"), std::string::npos);
  EXPECT_EQ(code.find("/*", 2), std::string::npos);
}

}  // namespace
}  // namespace penumbra
