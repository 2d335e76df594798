// Soak run (issue 11): a long synthetic run in real-time mode (mapping thread), checking that the system neither
// crashes nor deadlocks, that the per-frame tracking time stays stable and that memory stays bounded as the map
// design says (vo-strict: the window bounds everything held).
//
//   hslam_soak [--frames N] [--loop-frames S] [--speed X] [--out DIR] [--config FILE.yaml] [--mode vo-reuse]
//
// The synthetic scene's closed loop (S frames, the last one at the pose of the first) is rendered once and played
// lap after lap, so the camera moves continuously for N frames (default 10,000) and keeps revisiting the same room.
// Frames are given at X times the scene's frame rate (default 1: as a camera would, 0: as fast as possible).
// Outputs in DIR (default ./soak): soak.csv (frame, tracking ms, state, RSS MB every 100 frames) and soak.png
// (RSS and tracking time over the run). Exit status 0 when all checks hold:
//   - p95 of the tracking time of the last 1000 frames within 1.5x that of the first 1000 after a warm-up of 100;
//   - vo-strict: resident memory at the end within 10 % (at least 20 MB) of the resident memory at frame 1000;
//   - vo-reuse / slam (the global map grows by design, issue 9): resident memory growth per keyframe after the first
//     50 keyframes at most 0.5 MB, the statistics' memory per marginalised keyframe at most 0.5 MB too and within
//     0.1 MB of the measured growth (what the statistics count is what the process holds);
//   - no frame lost (the synthetic loop is easy) and one map segment.
#include "system/RunStatistics.h"

#include <visp3/hslam/vpHSlam.h>
#include <visp3/hslam/vpHSlamSyntheticScene.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <string>
#include <thread>
#include <vector>

namespace
{
constexpr unsigned int kWarmup = 100;
constexpr unsigned int kWindow = 1000;
constexpr unsigned int kRssEvery = 100;
constexpr double kMaxP95Ratio = 1.5;
constexpr double kMaxRssGrowthShare = 0.10;
constexpr double kMinRssGrowthAllowanceMb = 20.;
//! vo-reuse / slam: per-keyframe growth is measured from the first RSS sample with this many keyframes made.
constexpr unsigned int kKeyframesBeforeGrowth = 50;
//! Issue 9: at most this much memory per marginalised keyframe, MB; statistics and measurement agree within...
constexpr double kMaxMbPerKeyframe = 0.5;
constexpr double kMaxMbPerKeyframeDisagreement = 0.1;

struct Options {
  unsigned int frames = 10000;
  unsigned int loopFrames = 300;
  double speed = 1.;
  std::string out = "soak";
  std::string config;
  std::string mode; //!< system.mode, empty: the configuration's
};

Options parse(int argc, char **argv)
{
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "error: " << a << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--frames") {
      o.frames = static_cast<unsigned int>(std::stoul(next()));
    } else if (a == "--loop-frames") {
      o.loopFrames = static_cast<unsigned int>(std::stoul(next()));
    } else if (a == "--speed") {
      o.speed = std::stod(next());
    } else if (a == "--out") {
      o.out = next();
    } else if (a == "--config") {
      o.config = next();
    } else if (a == "--mode") {
      o.mode = next();
    } else {
      std::cerr << "usage: hslam_soak [--frames N] [--loop-frames S] [--speed X] [--out DIR] [--config FILE] "
                   "[--mode M]\n";
      std::exit(a == "--help" ? 0 : 2);
    }
  }
  if (o.frames < kWarmup + 2 * kWindow || o.loopFrames < 30) {
    std::cerr << "error: --frames must be at least " << kWarmup + 2 * kWindow << " and --loop-frames at least 30\n";
    std::exit(2);
  }
  return o;
}

double p95(std::vector<double> v)
{
  return hslam::percentile(std::move(v), 0.95);
}

//! Two stacked panels: RSS (MB) and tracking time (ms, p95 over 100 frames) against the frame index.
void plot(const std::string &path, const std::vector<std::pair<unsigned int, double>> &rss,
          const std::vector<double> &trackingMs, unsigned int frames)
{
  const int W = 1000, H = 640, left = 80, right = 20, top = 30, gap = 60;
  const int panelH = (H - top - gap - 40) / 2;
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
  auto panel = [&](int y0, const std::vector<std::pair<double, double>> &pts, const std::string &title,
                   const cv::Scalar &colour) {
    double lo = 1e300, hi = -1e300;
    for (const auto &p : pts) {
      lo = std::min(lo, p.second);
      hi = std::max(hi, p.second);
    }
    lo = std::min(0., lo);
    hi = hi <= lo ? lo + 1. : hi * 1.1;
    cv::rectangle(img, cv::Point(left, y0), cv::Point(W - right, y0 + panelH), cv::Scalar(0, 0, 0), 1);
    cv::putText(img, title, cv::Point(left, y0 - 8), cv::FONT_HERSHEY_SIMPLEX, 0.55, cv::Scalar(0, 0, 0), 1,
                cv::LINE_AA);
    for (int k = 0; k <= 4; ++k) {
      const double v = lo + (hi - lo) * k / 4.;
      const int y = y0 + panelH - static_cast<int>(panelH * k / 4.);
      cv::line(img, cv::Point(left - 4, y), cv::Point(left, y), cv::Scalar(0, 0, 0), 1);
      char label[32];
      std::snprintf(label, sizeof(label), "%.1f", v);
      cv::putText(img, label, cv::Point(8, y + 5), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    }
    std::vector<cv::Point> line;
    for (const auto &p : pts) {
      const int x = left + static_cast<int>((W - left - right) * p.first / std::max(1u, frames));
      const int y = y0 + panelH - static_cast<int>(panelH * (p.second - lo) / (hi - lo));
      line.emplace_back(x, y);
    }
    if (line.size() > 1) {
      cv::polylines(img, line, false, colour, 2, cv::LINE_AA);
    }
  };
  std::vector<std::pair<double, double>> rssPts, msPts;
  for (const auto &r : rss) {
    rssPts.emplace_back(r.first, r.second);
  }
  for (size_t i = 0; i + 100 <= trackingMs.size(); i += 100) {
    msPts.emplace_back(static_cast<double>(i + 50),
                       p95(std::vector<double>(trackingMs.begin() + static_cast<long>(i),
                                               trackingMs.begin() + static_cast<long>(i + 100))));
  }
  panel(top, rssPts, "resident memory (MB) against frame", cv::Scalar(200, 80, 0));
  panel(top + panelH + gap, msPts, "tracking time, p95 of each 100 frames (ms) against frame", cv::Scalar(0, 120, 0));
  char footer[128];
  std::snprintf(footer, sizeof(footer), "frames 0 .. %u", frames);
  cv::putText(img, footer, cv::Point(left, H - 12), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::imwrite(path, img);
}
} // namespace

int main(int argc, char **argv)
{
  const Options o = parse(argc, argv);
  try {
    std::filesystem::create_directories(o.out);
    vpHSlamSyntheticScene scene;
    scene.configure(640, 480, o.loopFrames, 30.0, 1);
    std::cout << "rendering the " << o.loopFrames << "-frame loop..." << std::flush;
    std::vector<vpImage<unsigned char>> loop(o.loopFrames - 1); // the last frame repeats the first pose
    for (unsigned int i = 0; i + 1 < o.loopFrames; ++i) {
      scene.render(i, loop[i]);
    }
    std::cout << " done" << std::endl;
    const vpCameraParameters cam = scene.getCameraParameters();
    const vpHSlamCamera camera(vpHSlamCamera::pinhole, scene.getWidth(), scene.getHeight(), cam.get_px(), cam.get_py(),
                               cam.get_u0(), cam.get_v0());
    vpHSlamParameters params;
    if (!o.config.empty()) {
      params.load(o.config);
    }
    if (!o.mode.empty()) {
      params.system.mode = vpHSlamParameters::parseMode(o.mode);
    }
    params.system.deterministic = false; // real-time mode: the mapping thread is what a soak must exercise
    vpHSlam slam(camera, params);

    std::vector<double> trackingMs;
    trackingMs.reserve(o.frames);
    std::vector<std::pair<unsigned int, double>> rss;
    std::vector<unsigned int> rssKeyframes; //!< keyframes made when each RSS sample was taken
    std::ofstream csv(o.out + "/soak.csv");
    csv << "frame,tracking_ms,state,rss_mb,keyframes\n";
    unsigned int lost = 0;
    const double dt = 1. / scene.getFrameRate();
    const auto start = std::chrono::steady_clock::now();
    for (unsigned int k = 0; k < o.frames; ++k) {
      if (o.speed > 0.) {
        std::this_thread::sleep_until(start + std::chrono::duration<double>(k * dt / o.speed));
      }
      const double t0 = hslam::nowMs();
      const vpHSlam::State state = slam.track(loop[k % loop.size()], k * dt);
      const double ms = hslam::nowMs() - t0;
      trackingMs.push_back(ms);
      lost += state == vpHSlam::stateLost ? 1u : 0u;
      csv << k << "," << ms << "," << static_cast<int>(state) << ",";
      if (k % kRssEvery == 0 || k + 1 == o.frames) {
        const double mb = hslam::processMemoryMb("VmRSS:");
        rss.emplace_back(k, mb);
        rssKeyframes.push_back(slam.getStatistics().keyframes);
        csv << mb << "," << rssKeyframes.back();
      } else {
        csv << ",";
      }
      csv << "\n";
      if (k % 1000 == 0) {
        std::cout << "frame " << k << ": rss " << hslam::processMemoryMb("VmRSS:") << " MB" << std::endl;
      }
    }
    slam.synchronize();
    const vpHSlam::Statistics s = slam.getStatistics();
    plot(o.out + "/soak.png", rss, trackingMs, o.frames);

    const double first = p95(std::vector<double>(trackingMs.begin() + kWarmup, trackingMs.begin() + kWarmup + kWindow));
    const double last = p95(std::vector<double>(trackingMs.end() - kWindow, trackingMs.end()));
    double rssAt1000 = 0.;
    for (const auto &r : rss) {
      if (r.first <= kWarmup + kWindow) {
        rssAt1000 = r.second;
      }
    }
    const double rssEnd = rss.back().second;
    const double allowance = std::max(kMinRssGrowthAllowanceMb, kMaxRssGrowthShare * rssAt1000);
    std::cout << "frames " << s.frames << ", tracked " << s.trackedFrames << ", lost " << lost << ", segments "
              << s.segments << ", keyframes " << s.keyframes << ", mapping skipped " << s.mappingSkippedFrames
              << "\ntracking p95: first 1000 (after " << kWarmup << ") " << first << " ms, last 1000 " << last
              << " ms, ratio " << last / first << " (limit " << kMaxP95Ratio << ")\nresident memory: at frame "
              << kWarmup + kWindow << " " << rssAt1000 << " MB, at the end " << rssEnd << " MB, peak "
              << hslam::processMemoryMb("VmHWM:") << " MB (growth allowed " << allowance << " MB)\nwrote " << o.out
              << "/soak.csv, " << o.out << "/soak.png" << std::endl;
    bool ok = true;
    if (!(last <= kMaxP95Ratio * first)) {
      std::cout << "FAIL: tracking time grew" << std::endl;
      ok = false;
    }
    if (params.system.mode == vpHSlamParameters::modeVoStrict) {
      if (!(rssEnd <= rssAt1000 + allowance)) {
        std::cout << "FAIL: memory grew" << std::endl;
        ok = false;
      }
    } else {
      // The global map keeps every keyframe: growth per keyframe once the first 50 are made (window, pools and
      // vocabulary are in place by then), against what the statistics count per marginalised keyframe. Two
      // measures: from that sample to the end (what the issue bounds, 0.5 MB), and the sustained growth, the median
      // of the growth per keyframe between consecutive samples. The second is the one compared with the statistics:
      // resident memory also rises in one-off steps of a whole frame (7 MB at 640x480) when one more frame than
      // ever before is in flight (the frame pool keeps it, up to its bound), which is not memory per keyframe
      // (4000 frames: 0-2 such steps, moving the first measure by 0.05 MB per keyframe each).
      size_t from = rss.size() - 1;
      for (size_t i = 0; i < rss.size(); ++i) {
        if (rssKeyframes[i] >= kKeyframesBeforeGrowth) {
          from = i;
          break;
        }
      }
      const double keyframes = static_cast<double>(rssKeyframes.back()) - rssKeyframes[from];
      const double growth = keyframes > 0. ? (rss.back().second - rss[from].second) / keyframes : 0.;
      std::vector<double> slopes;
      for (size_t i = from + 1; i < rss.size(); ++i) {
        const double made = static_cast<double>(rssKeyframes[i]) - rssKeyframes[i - 1];
        if (made > 0.) {
          slopes.push_back((rss[i].second - rss[i - 1].second) / made);
        }
      }
      double sustained = std::numeric_limits<double>::quiet_NaN();
      if (!slopes.empty()) {
        std::nth_element(slopes.begin(), slopes.begin() + static_cast<std::ptrdiff_t>(slopes.size() / 2), slopes.end());
        sustained = slopes[slopes.size() / 2];
      }
      std::cout << "global map: " << s.marginalizedKeyframes << " marginalised keyframes kept (" << s.culledKeyframes
                << " culled), " << s.globalPoints << " points; resident memory growth per keyframe after "
                << kKeyframesBeforeGrowth << " keyframes: " << growth << " MB over " << keyframes
                << " keyframes, sustained " << sustained << " MB (median over " << slopes.size()
                << " intervals); statistics: " << s.mapMemoryMbPerKeyframe << " MB per marginalised keyframe"
                << std::endl;
      if (!(keyframes > 0.) || !(growth <= kMaxMbPerKeyframe) || !(s.mapMemoryMbPerKeyframe <= kMaxMbPerKeyframe) ||
          !(std::fabs(sustained - s.mapMemoryMbPerKeyframe) <= kMaxMbPerKeyframeDisagreement)) {
        std::cout << "FAIL: memory per keyframe" << std::endl;
        ok = false;
      }
    }
    if (lost > 0 || s.segments != 1) {
      std::cout << "FAIL: tracking was lost" << std::endl;
      ok = false;
    }
    return ok ? 0 : 1;
  } catch (const std::exception &e) {
    std::cerr << "error: " << e.what() << std::endl;
    return 1;
  }
}
