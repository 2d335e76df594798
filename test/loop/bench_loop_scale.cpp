// Loop closure at scale (issue 50): the two costs of loop closure that grow with the map, on maps of 1,000, 3,000 and
// 10,000 stored keyframes built synthetically (no images: what is timed is the search and the graph, not the
// keypoints, whose cost per keyframe does not depend on the map):
//   - BM_LoopQuery: one keyframe's query of the keyframe database (the loop closer's rules: candidates not among its
//     10 neighbours in time, co-visibility groups of 3 neighbours, floor at its lowest score with them). Each keyframe
//     holds 500 words of the shipped vocabulary's 413,203, drawn as a run that goes round the same room: 250 places a
//     lap, consecutive places sharing half their words, a revisit re-detecting 70 % of the place's words;
//   - BM_LoopCorrection: solveLoopCorrection() on a chain of keyframes (pose-pose edges to the 2 previous ones, as the
//     window leaves them), 7 window keyframes held, one loop from the newest stored keyframe back to the first; with
//     laps_linked 4, each keyframe is also joined to its place and the two next to it on each of the 4 laps before
//     (a map re-used lap after lap, 14 edges a keyframe, as hslam_many_laps' graph has about 15).
// Peak resident memory of the process is printed at the end (VmHWM). Labelled "benchmark": not run by CI.
#include "loop/KeyframeDatabase.h"
#include "loop/LoopCorrection.h"

#include "CircleRun.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>

namespace
{
constexpr std::uint32_t kWords = 413203; // the shipped vocabulary
constexpr int kWordsPerKeyframe = 500;
constexpr int kPlacesPerLap = 250;
constexpr int kWindow = 7;

hslam::BowVector toBow(std::vector<std::uint32_t> words)
{
  std::sort(words.begin(), words.end());
  words.erase(std::unique(words.begin(), words.end()), words.end());
  hslam::BowVector bow;
  for (std::uint32_t w : words) {
    bow.push_back({w, 1. / static_cast<double>(words.size())});
  }
  return bow;
}

//! The database of \e n keyframes (see the file comment), built once per size.
const hslam::KeyframeDatabase &database(int n)
{
  static std::map<int, std::unique_ptr<hslam::KeyframeDatabase>> made;
  auto &db = made[n];
  if (!db) {
    std::mt19937 rng(7);
    std::uniform_int_distribution<std::uint32_t> word(0, kWords - 1);
    std::vector<std::vector<std::uint32_t>> places(kPlacesPerLap);
    for (int p = 0; p < kPlacesPerLap; ++p) {
      for (int i = 0; i < kWordsPerKeyframe; ++i) { // the first half: the previous place's second half
        const bool shared = p > 0 && i < kWordsPerKeyframe / 2;
        places[static_cast<size_t>(p)].push_back(
            shared ? places[static_cast<size_t>(p - 1)][static_cast<size_t>(i + kWordsPerKeyframe / 2)] : word(rng));
      }
    }
    db = std::make_unique<hslam::KeyframeDatabase>(kWords);
    for (int k = 0; k < n; ++k) {
      std::vector<std::uint32_t> words = places[static_cast<size_t>(k % kPlacesPerLap)];
      for (std::uint32_t &w : words) {
        w = rng() % 10 < 3 ? word(rng) : w; // not re-detected: another word
      }
      db->add(k, toBow(words));
    }
  }
  return *db;
}

void BM_LoopQuery(benchmark::State &state)
{
  const int n = static_cast<int>(state.range(0));
  const hslam::KeyframeDatabase &db = database(n);
  std::mt19937 rng(11);
  size_t candidates = 0, queries = 0;
  for (auto _ : state) {
    const int id = 3 + static_cast<int>(rng() % static_cast<unsigned int>(n - 3));
    hslam::BowVector bow;
    db.vectorOf(id, bow);
    const std::vector<double> scores = db.scoresWith(bow, {id - 1, id - 2, id - 3});
    hslam::KeyframeDatabase::Query q;
    q.minScore = *std::min_element(scores.begin(), scores.end());
    q.excluded = [id](int c) { return std::abs(c - id) <= 10; };
    q.covisible = [n](int c) {
      std::vector<int> out;
      for (int d = 1; d <= 3; ++d) {
        for (int o : {c - d, c + d}) {
          if (o >= 0 && o < n) {
            out.push_back(o);
          }
        }
      }
      return out;
    };
    candidates += db.query(bow, q).size();
    ++queries;
  }
  state.counters["candidates_per_query"] = static_cast<double>(candidates) / static_cast<double>(queries);
  state.counters["database_MB"] = db.memoryBytes() / 1048576.;
}
BENCHMARK(BM_LoopQuery)->Arg(1000)->Arg(3000)->Arg(10000)->Unit(benchmark::kMillisecond);

//! Camera \e k of a run round a circle (a lap every kPlacesPerLap keyframes).
hslam::SE3d cameraPose(int k, double drift)
{
  return hslam_test::circleCamera(k, kPlacesPerLap, drift);
}

//! An edge between stored keyframes \e from and \e to, measured by the drifting odometry.
void addOdometryEdge(hslam::GlobalMap &map, int from, int to)
{
  hslam::PosePoseEdge e;
  e.from = from;
  e.to = to;
  e.toMfrom = cameraPose(to, 1e-4) * cameraPose(from, 1e-4).inverse();
  map.addPosePoseEdge(e);
}

void BM_LoopCorrection(benchmark::State &state)
{
  const int n = static_cast<int>(state.range(0)), lapsLinked = static_cast<int>(state.range(1));
  hslam::GlobalMap map;
  for (int k = 0; k < n; ++k) {
    hslam::GlobalKeyframe g;
    g.id = k;
    g.cMw = cameraPose(k, 1e-4); // the odometry drifts
    map.add(g);
    for (int d = 1; d <= 2 && k - d >= 0; ++d) {
      addOdometryEdge(map, k - d, k);
    }
    // A map re-used lap after lap: the same place and its two neighbours on each of the last lapsLinked laps.
    for (int lap = 1; lap <= lapsLinked; ++lap) {
      for (int d = -1; d <= 1; ++d) {
        const int other = k - lap * kPlacesPerLap + d;
        if (other >= 0 && other < k) {
          addOdometryEdge(map, other, k);
        }
      }
    }
  }
  std::map<int, hslam::SE3d> window;
  for (int k = n; k < n + kWindow; ++k) {
    window[k] = cameraPose(k, 1e-4);
    hslam::PosePoseEdge e;
    e.from = k - 1;
    e.to = k;
    e.toMfrom = cameraPose(k, 1e-4) * cameraPose(k - 1, 1e-4).inverse();
    map.addPosePoseEdge(e);
  }
  hslam::DetectedLoop loop;
  loop.keyframe = n - 1;
  loop.candidate = (n - 1) % kPlacesPerLap == 0 ? 0 : (n - 1) % kPlacesPerLap; // the same place on the first lap
  loop.SkeyframeCandidate = hslam::Sim3d(cameraPose(n - 1, 0.) * cameraPose(loop.candidate, 0.).inverse(), 1.);
  size_t moved = 0;
  for (auto _ : state) {
    std::vector<hslam::PoseGraphEdge> constraints;
    std::vector<std::pair<int, hslam::Sim3d>> solution;
    if (!hslam::solveLoopCorrection(map, 0, window, constraints, loop, solution)) {
      state.SkipWithError("pose graph failed");
      return;
    }
    moved = solution.size();
  }
  state.counters["keyframes_moved"] = static_cast<double>(moved);
}
BENCHMARK(BM_LoopCorrection)
    ->ArgsProduct({{1000, 3000, 10000}, {0}})
    ->ArgNames({"keyframes", "laps_linked"})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);
// Past 500 keyframes the lap-linked map's older keyframes move as one (kLoopMaxFreeKeyframes); bent whole, the
// 10,000 took 379 s (docs/global-map-and-loops.md).
BENCHMARK(BM_LoopCorrection)
    ->ArgsProduct({{1000, 3000, 10000}, {4}})
    ->ArgNames({"keyframes", "laps_linked"})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);

//! Peak resident memory, printed when the program ends.
struct PeakMemory {
  ~PeakMemory()
  {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line)) {
      if (line.rfind("VmHWM:", 0) == 0) {
        std::printf("peak resident memory (%s)\n", line.c_str());
      }
    }
  }
} peakMemory;
} // namespace
