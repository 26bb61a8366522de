// Checkpoint/resume: a run resumed from a checkpoint ends bit-identical to one that never stopped
// (reference: the CPU backend is deterministic — gather sums in a fixed neighbour order, stable
// counting sort, fixed-order reductions — so the same state must give the same bits).
// Through splitting events too (debris -> turbidity): the checkpoint holds a grown particle count
// and daughters of half h; the resumed store keeps the scene's reserved capacity, the split totals
// and the daughters' time-step limit, so later splits and steps are the same as without the stop.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

#include "fsi/bullet_world.hpp"
#include "tools/runner.hpp"

namespace fs = std::filesystem;

namespace {

const char* kScene = R"(name: resume_check
dimensions: 2
resolution: {particle_spacing: 0.01, smoothing_ratio: 1.3}
time: {end: 0.06, cfl: 0.2}
gravity: [0, -9.81]
materials:
  water: {model: newtonian, density: 1000, viscosity: 1.0e-3, sound_speed: 20}
walls:
  - box: {min: [0, 0], max: [0.4, 0.25]}
fluids:
  - {material: water, box: {min: [0, 0], max: [0.1, 0.2]}}
probes:
  - {name: front, type: front_position, material: water, axis: x}
  - {name: vmax, type: max_speed}
output: {every: 0.01, vtk: true}
)";

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

turbid::tools::RunRequest request(const fs::path& scene, const fs::path& out) {
  turbid::tools::RunRequest r;
  r.scene_file = scene;
  r.out = out;
  r.backend = "cpu";
  r.progress = false;
  return r;
}

// A Bingham debris column (tau_y = 20 Pa) collapsing into water in a closed tank (the scene of
// test_transition.cpp at twice the spacing), splitting into turbidity at the wet face where
// sqrt(J2) > 20.1 Pa: just above the yield stress, so mothers split one by one as the face yields
// (below tau_y nearly all splits come in the first steps, from the start-up transient).
const char* kSplittingScene = R"(name: resume_split_check
dimensions: 2
resolution: {particle_spacing: 0.02, smoothing_ratio: 2.0}
time: {end: 0.06, cfl: 0.2}
gravity: [0, -9.81]
numerics: {viscosity: {type: laminar}}
materials:
  water: {model: newtonian, density: 1000, viscosity: 1.0e-3, sound_speed: 20}
  debris: {model: bingham, density: 1950, viscosity: 0.1, yield_stress: 20, papanastasiou_exponent: 100,
           sound_speed: 20}
  turbidity: {model: newtonian, density: 1950, viscosity: 1.0e-3, sound_speed: 20}
walls:
  - box: {min: [0, 0], max: [0.6, 0.3]}
fluids:
  - {material: debris, box: {min: [0, 0], max: [0.2, 0.2]}}
  - {material: water, box: {min: [0.2, 0], max: [0.6, 0.2]}}
transitions:
  - {from: debris, to: turbidity, when: {effective_shear_stress_above: 20.1}, where: interface}
capacity: {factor: 3.0}
probes:
  - {name: debris_mass, type: material_mass, material: debris}
  - {name: turbidity_mass, type: material_mass, material: turbidity}
  - {name: vmax, type: max_speed}
output: {every: 0.01, vtk: true}
)";

nlohmann::json checkpoint_state(const fs::path& run_dir) {
  std::ifstream in(run_dir / "checkpoint" / "checkpoint.json");
  return nlohmann::json::parse(in).at("state");
}

struct ResumeRuns {
  nlohmann::json full, part, resumed;
  nlohmann::json checkpoint_before_resume;  // the state the resumed run started from
};

}  // namespace

// Runs the scene to 0.06 s without stopping, and again stopped at 0.035 s (checkpoints every
// 0.02 s) and resumed from the checkpoint at 0.02 s; both runs must write the same bytes.
ResumeRuns check_resume(const std::string& scene_text) {
  ResumeRuns r;
  const fs::path dir = fs::temp_directory_path() / ("turbid_resume_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path scene = dir / "scene.yaml";
  std::ofstream(scene) << scene_text;

  // Uninterrupted run to 0.06 s, with the same checkpoints as the interrupted one (they change
  // nothing in the run) so that the last checkpoints of both can be compared field by field.
  auto uninterrupted = request(scene, dir / "full");
  uninterrupted.checkpoint_every = 0.02;
  r.full = turbid::tools::run_scene(uninterrupted);
  EXPECT_EQ(r.full.at("status"), "completed");

  // Interrupted run: stops at 0.035 s with a checkpoint taken at 0.02 s, then resumes to 0.06 s.
  auto first = request(scene, dir / "split");
  first.end_time = 0.035;
  first.checkpoint_every = 0.02;
  r.part = turbid::tools::run_scene(first);
  EXPECT_EQ(r.part.at("status"), "completed");
  r.checkpoint_before_resume = checkpoint_state(dir / "split");
  turbid::tools::RunRequest again;
  again.resume = dir / "split";
  again.backend = "cpu";
  again.progress = false;
  again.end_time = 0.06;
  again.checkpoint_every = 0.02;
  r.resumed = turbid::tools::run_scene(again);
  EXPECT_EQ(r.resumed.at("status"), "completed");

  EXPECT_EQ(r.full.at("steps"), r.resumed.at("steps"));
  EXPECT_EQ(r.full.at("simulated_time").get<double>(), r.resumed.at("simulated_time").get<double>());
  // run.json: counts (the wall constraint's put-backs, their rate per fluid particle-step, impulse
  // and energy too: restored from the checkpoint, the resumed run adds to them in the same order), capacity,
  // split totals, masses and momenta (exact: same bits, same sums).
  for (const char* key : {"particles", "particles_end", "removed_particles", "capacity", "splits", "daughters_created",
                          "splits_refused", "fluid_mass_start", "fluid_mass_end", "fluid_momentum_start",
                          "fluid_momentum_end", "materials", "fluid_put_back_on_walls", "fluid_put_backs_per_particle_step",
                          "wall_constraint_impulse", "wall_constraint_energy"}) {
    EXPECT_EQ(r.full.contains(key), r.resumed.contains(key)) << key;
    if (r.full.contains(key)) {
      EXPECT_EQ(r.full.at(key), r.resumed.at(key)) << "run.json '" << key << "' after resume";
    }
  }
  // Every frame and every probe row must match byte for byte.
  int frames = 0;
  for (const auto& e : fs::directory_iterator(dir / "full")) {
    if (e.path().extension() != ".vtp") continue;
    const fs::path twin = dir / "split" / e.path().filename();
    EXPECT_TRUE(fs::exists(twin)) << twin;
    EXPECT_TRUE(slurp(e.path()) == slurp(twin)) << e.path().filename() << " differs after resume";
    ++frames;
  }
  EXPECT_GE(frames, 6);
  EXPECT_EQ(slurp(dir / "full" / "probes.csv"), slurp(dir / "split" / "probes.csv"));
  EXPECT_EQ(slurp(dir / "full" / "particles.pvd"), slurp(dir / "split" / "particles.pvd"));
  if (fs::exists(dir / "full" / "forces.csv")) {
    EXPECT_EQ(slurp(dir / "full" / "forces.csv"), slurp(dir / "split" / "forces.csv"));
  }
  // The last checkpoint (after the resume point): every checkpointed field, including those the
  // frames leave out (mass, smoothing length, acceleration), and the saved state but the wall time.
  auto state_full = checkpoint_state(dir / "full");
  auto state_resumed = checkpoint_state(dir / "split");
  EXPECT_GT(state_resumed.at("time").get<double>(), 0.035) << "a checkpoint written after the resume";
  state_full.erase("wall_seconds");
  state_resumed.erase("wall_seconds");
  EXPECT_EQ(state_full, state_resumed);
  int fields = 0;
  for (const auto& e : fs::directory_iterator(dir / "full" / "checkpoint")) {
    if (e.path().extension() != ".bin") continue;
    EXPECT_TRUE(slurp(e.path()) == slurp(dir / "split" / "checkpoint" / e.path().filename()))
        << "checkpointed field " << e.path().filename() << " differs after resume";
    ++fields;
  }
  EXPECT_GE(fields, 8);
  fs::remove_all(dir);
  return r;
}

TEST(CheckpointResume, ResumedRunIsBitIdenticalToUninterruptedRun) { check_resume(kScene); }

// Probes on their own schedule (issue #25 item 4): the resumed run picks the schedule up from the
// checkpoint's time, so probes.csv has the same rows, byte for byte, every 2.5 ms and every step.
TEST(CheckpointResume, ResumedRunWithProbesOnTheirOwnScheduleIsBitIdentical) {
  for (const char* every : {"0.0025", "step"}) {
    std::string scene = kScene;
    const std::string out = "output: {every: 0.01, vtk: true}";
    ASSERT_NE(scene.find(out), std::string::npos);
    scene.replace(scene.find(out), out.size(), "output: {every: 0.01, vtk: true, probes_every: " + std::string(every) + "}");
    SCOPED_TRACE(every);
    check_resume(scene);
  }
}

// With particle shifting the next drift uses the shifting velocity of the last force pass, which
// the checkpoint must therefore hold (like the acceleration).
TEST(CheckpointResume, ResumedRunWithShiftingIsBitIdentical) {
  check_resume(std::string(kScene) + "numerics: {shifting: {coefficient: 2.0}}\n");
}

// A free body (issue #8) straddling the column's face: the checkpoint holds its exact state (JSON
// numbers read back as the same doubles) and the fluid load of the last force pass, which the first
// kick after the resume needs; forces.csv (with the body's position, orientation and velocities)
// must match byte for byte too.
TEST(CheckpointResume, ResumedRunWithAFreeBodyIsBitIdentical) {
  const auto r = check_resume(std::string(kScene) +
                              "structures:\n  - {name: box, box: {size: [0.04, 0.04]}, position: [0.1, 0.1], "
                              "rotation: 15, motion: free, density: 800}\n");
  EXPECT_EQ(r.full.at("status"), "completed");
}

// A free box resting on the floor with a DEM contact material, on a spring to an anchor (issue #8):
// the checkpoint also holds the open contacts' tangential springs (the body substeps continue
// them) and the mean contact force that forces.csv reports.
TEST(CheckpointResume, ResumedRunWithContactsAndASpringIsBitIdentical) {
  const auto r = check_resume(std::string(kScene) +
                              "structures:\n  - {name: box, box: {size: [0.04, 0.04]}, position: [0.32, 0.02], "
                              "motion: free, density: 800,\n     contact: {youngs_modulus: 1.0e7, restitution: 0.5, "
                              "friction: 0.4}}\nconstraints:\n  - {type: spring, a: {structure: box, point: [0.33, "
                              "0.04]}, b: {anchor: [0.38, 0.2]}, stiffness: 50, damping: 0.5}\n");
  EXPECT_EQ(r.full.at("status"), "completed");
  EXPECT_FALSE(r.checkpoint_before_resume.at("contacts").empty()) << "the box should be on the floor at the checkpoint";
}

// A prescribed paddle (issue #8) oscillating and turning in the column's face: its path is a function
// of the solver's time alone, so the checkpoint needs nothing more than the time and the particles;
// the resumed run must place it at the same times with the same bits (frames, forces.csv with its
// kinematics columns, every checkpointed field).
TEST(CheckpointResume, ResumedRunWithAPrescribedBodyIsBitIdentical) {
  const auto r = check_resume(std::string(kScene) +
                              "structures:\n  - {name: paddle, box: {size: [0.02, 0.1]}, position: [0.12, 0.08], "
                              "motion: prescribed,\n     path: {oscillation: {amplitude: [0.02, 0.005], "
                              "angular_amplitude: 10, period: 0.1}}}\n");
  EXPECT_EQ(r.full.at("status"), "completed");
}

// The same with a bullet body (motion: bullet, fsi/bullet_world.hpp): the checkpoint holds the
// mirror's state and Bullet's own exact state (transform basis and origin, velocities, the impulse
// gathered since the last Bullet step), which a resume restores, so the run stays bit-identical.
TEST(CheckpointResume, ResumedRunWithABulletBodyIsBitIdentical) {
  if (!turbid::fsi::bullet_available()) GTEST_SKIP() << "built without Bullet";
  const auto r = check_resume(std::string(kScene) +
                              "structures:\n  - {name: box, box: {size: [0.04, 0.04]}, position: [0.1, 0.1], "
                              "rotation: 15, motion: bullet, density: 800}\n");
  EXPECT_EQ(r.full.at("status"), "completed");
}

// Splits before the checkpoint (0.02 s), between it and the stop (0.035 s) and after the resume:
// the checkpoint holds more particles than the scene builds, some with h/2, and the resumed run
// must go on splitting exactly as the uninterrupted one (same totals, same capacity).
TEST(CheckpointResume, ResumedRunThroughSplittingIsBitIdentical) {
  const ResumeRuns r = check_resume(kSplittingScene);
  const std::size_t at_checkpoint = r.checkpoint_before_resume.at("splits").get<std::size_t>();
  const std::size_t at_stop = r.part.at("splits").get<std::size_t>();
  const std::size_t at_end = r.full.at("splits").get<std::size_t>();
  std::printf("splits: %zu by the checkpoint (t = %.4f s), %zu by the stop, %zu by the end; %zu particles at the end\n",
              at_checkpoint, r.checkpoint_before_resume.at("time").get<double>(), at_stop, at_end,
              r.full.at("particles_end").get<std::size_t>());
  EXPECT_GT(at_checkpoint, 0u) << "the checkpoint must hold daughters";
  EXPECT_GT(at_stop, at_checkpoint) << "splits between the checkpoint and the stop (redone after the resume)";
  EXPECT_GT(at_end, at_stop) << "splits after the stop";
  EXPECT_EQ(r.checkpoint_before_resume.at("smallest_smoothing_length").get<double>(), double(0.5f * 0.04f))
      << "daughters' h, h0/2 = 0.02 m";
  EXPECT_EQ(r.full.at("splits_refused").get<std::size_t>(), 0u);
  EXPECT_EQ(r.resumed.at("daughters_created").get<std::size_t>(), 3 * at_end);
  EXPECT_EQ(r.resumed.at("particles_end").get<std::size_t>(),
            r.resumed.at("particles").get<std::size_t>() + 3 * at_end) << "particles: start + daughters";
  // The store reserves the scene's capacity (factor 3 of the particles built), not the count saved.
  EXPECT_EQ(r.resumed.at("capacity").get<std::size_t>(),
            std::size_t(std::ceil(3.0 * double(r.resumed.at("particles").get<std::size_t>()))));
}

// Implicit viscosity (issue #20): a Bingham column (no stated cap, so its viscosity at rest,
// m tau_y + mu_p = 2000 Pa s, is integrated implicitly, with the full stress) collapsing in a
// tank with no-slip mDBC walls, against a fixed structure. The next step's first viscous solve reads
// the mirrored wall velocities and the effective viscosities of the last force pass, and the
// structure's viscous load waits half a step in viscous_pending: the checkpoint must hold them all.
constexpr const char* kImplicitScene = R"(name: resume_implicit_viscosity
dimensions: 2
resolution: {particle_spacing: 0.01, smoothing_ratio: 1.3}
time: {end: 0.06, cfl: 0.2}
gravity: [0, -9.81]
numerics:
  viscosity: {type: laminar, integration: auto, stress: full}
  boundary: {type: mdbc, velocity: no_slip}
materials:
  debris: {model: bingham, density: 1800, viscosity: 0.5, yield_stress: 20, papanastasiou_exponent: 100,
           sound_speed: 20}
walls:
  - box: {min: [0, 0], max: [0.4, 0.25]}
structures:
  - {name: block, box: {size: [0.04, 0.04]}, position: [0.2, 0.03]}
fluids:
  - {material: debris, box: {min: [0, 0], max: [0.12, 0.2]}}
probes:
  - {name: front, type: front_position, material: debris, axis: x}
output: {every: 0.01, vtk: true}
)";

TEST(CheckpointResume, ResumedRunWithImplicitViscosityAndMdbcIsBitIdentical) {
  const auto r = check_resume(kImplicitScene);
  EXPECT_EQ(r.full.at("status"), "completed");
  EXPECT_GT(r.full.at("viscous_solves").get<long>(), 0) << "the implicit solve must run";
}

// The same on DBC walls, whose no-slip velocity (the default with the full stress) is mirrored at
// their ghost nodes while their density comes from continuity.
TEST(CheckpointResume, ResumedRunWithImplicitViscosityAndNoSlipDbcIsBitIdentical) {
  std::string scene = kImplicitScene;
  const std::string mdbc = "  boundary: {type: mdbc, velocity: no_slip}\n";
  const auto at = scene.find(mdbc);
  ASSERT_NE(at, std::string::npos);
  scene.replace(at, mdbc.size(), "  boundary: {type: dbc}\n");
  const auto r = check_resume(scene);
  EXPECT_EQ(r.full.at("status"), "completed");
  EXPECT_EQ(r.full.at("wall_treatment").at("type"), "dbc");
  EXPECT_EQ(r.full.at("wall_treatment").at("velocity"), "no_slip") << "the full stress's default";
  EXPECT_GT(r.full.at("viscous_solves").get<long>(), 0) << "the implicit solve must run";
}

// Issue #25: the wall options are state-free (recomputed from positions and velocities each step),
// so a run with the wall-normal artificial viscosity and the log-law wall function resumes bit for
// bit; run.json says which approach and which wall function the run used.
TEST(CheckpointResume, ResumedRunWithWallNormalViscosityAndWallFunctionIsBitIdentical) {
  std::string scene = kScene;
  const std::string walls = "walls:\n";
  const auto at = scene.find(walls);
  ASSERT_NE(at, std::string::npos);
  scene.insert(at,
               "numerics:\n  viscosity: {type: artificial, alpha: 0.02, walls: normal}\n"
               "  boundary: {type: mdbc, wall_function: {roughness: 0.001}}\n");
  const auto r = check_resume(scene);
  EXPECT_EQ(r.full.at("status"), "completed");
  EXPECT_EQ(r.full.at("wall_treatment").at("type"), "mdbc");
  EXPECT_EQ(r.full.at("wall_treatment").at("artificial_viscosity_approach"), "normal");
  EXPECT_EQ(r.full.at("wall_treatment").at("wall_function").at("roughness_m").get<double>(), 0.001);
}

