/*
 * H-SLAM for ViSP.
 */
#include "mapping/WindowOptimizer.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

namespace hslam
{
namespace
{
//! LM damping factors after an accepted / rejected step (DSO FullSystemOptimize: lambda *= 0.25 / *= 1e2).
constexpr double kLambdaAcceptFactor = 0.25;
constexpr double kLambdaRejectFactor = 100.;
//! Beyond this damping a step cannot lower the energy any more: stop.
constexpr double kMaxLambda = 1e8;

std::string where(int line)
{
  return std::string(__FILE__) + ":" + std::to_string(line) + ": ";
}

double elapsedMs(std::chrono::steady_clock::time_point t0)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
} // namespace

WindowOptimizer::WindowOptimizer(const vpHSlamParameters &params)
    : m_mapper(params.mapper), m_gradientWeightC(params.tracker.gradientWeightC),
      m_affinePriorA(params.tracker.affinePriorA), m_affinePriorB(params.tracker.affinePriorB),
      m_affinePriorAFree(params.tracker.affinePriorA), m_affinePriorBFree(params.tracker.affinePriorB),
      m_affinePriorACalib(params.tracker.affinePriorACalibrated),
      m_affinePriorBCalib(params.tracker.affinePriorBCalibrated)
{
  if (m_mapper.windowSize + 1 > kMaxWindowKeyframes || m_mapper.windowSize < 2) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           where(__LINE__) + "mapper.windowSize = " + std::to_string(m_mapper.windowSize) +
                               " is outside [2, " + std::to_string(kMaxWindowKeyframes - 1) + "]");
  }
  m_anchors = params.globalMap.anchors;
  m_anchorPixelWeight = params.globalMap.anchorPixelWeight;
  m_anchorHuberPx = params.globalMap.anchorHuberPx;
  m_anchorMinForScale = params.globalMap.anchorMinForScale;
  m_settings.huberThreshold = params.tracker.huberThreshold;
  m_settings.outlierEnergy = params.tracker.outlierEnergyPerPixel * kPatternSize;
  m_pool = std::make_unique<WorkerPool>(params.system.workerThreads);
  m_workerAcc.resize(static_cast<size_t>(m_pool->participants()));
  m_workerEnergy.resize(static_cast<size_t>(m_pool->participants()));
}

void WindowOptimizer::setPhotometricallyCalibrated(bool calibrated)
{
  m_affinePriorA = calibrated ? m_affinePriorACalib : m_affinePriorAFree;
  m_affinePriorB = calibrated ? m_affinePriorBCalib : m_affinePriorBFree;
}

void WindowOptimizer::addKeyframe(const KeyframePtr &keyframe)
{
  m_accCurrent = false;
  if (!keyframe || !keyframe->frame || keyframe->frame->pyramid.numLevels() < 1) {
    throw vpHSlamException(vpHSlamException::invalidArgument, where(__LINE__) + "keyframe without frame or pyramid");
  }
  if (static_cast<int>(m_frames.size()) >= kMaxWindowKeyframes) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           where(__LINE__) + "window full (" + std::to_string(kMaxWindowKeyframes) +
                               " keyframes): marginalise before adding keyframe " + std::to_string(keyframe->id()));
  }
  if (m_frames.empty()) {
    m_settings.K = keyframe->frame->pyramid.level(0).K;
  }
  const int index = static_cast<int>(m_frames.size());
  WindowFrame wf;
  wf.kf = keyframe;
  m_frames.push_back(wf);
  KeyframeState s;
  s.cMw = keyframe->frame->cMw;
  s.a = keyframe->frame->affine.a;
  s.b = keyframe->frame->affine.b;
  m_states.push_back(s);
  m_prior.addFrame();
  keyframe->inWindow = true;
  if (m_gaugeKeyframeId < 0) {
    m_gaugeKeyframeId = keyframe->id();
  }
  for (WindowPoint &p : m_points) {
    WindowResidual r;
    r.target = index;
    p.residuals.push_back(r);
  }
}

std::vector<KeyframePtr> WindowOptimizer::keyframes() const
{
  std::vector<KeyframePtr> out;
  for (const WindowFrame &f : m_frames) {
    out.push_back(f.kf);
  }
  return out;
}

void WindowOptimizer::registerPoint(int host, int pointIndex)
{
  WindowPoint p;
  p.host = host;
  p.pointIndex = pointIndex;
  p.residuals.reserve(static_cast<size_t>(kMaxWindowKeyframes));
  for (int t = 0; t < static_cast<int>(m_frames.size()); ++t) {
    if (t != host) {
      WindowResidual r;
      r.target = t;
      p.residuals.push_back(r);
    }
  }
  m_points.push_back(std::move(p));
}

void WindowOptimizer::syncStatesAndPoints()
{
  for (size_t i = 0; i < m_frames.size(); ++i) {
    const Frame &f = *m_frames[i].kf->frame;
    m_states[i].cMw = f.cMw;
    m_states[i].a = f.affine.a;
    m_states[i].b = f.affine.b;
  }
  // Release points whose status was changed outside (outlier / marginalised by the mapper).
  std::vector<char> release(m_points.size(), 0);
  bool any = false;
  for (size_t i = 0; i < m_points.size(); ++i) {
    const WindowPoint &p = m_points[i];
    if (m_frames[static_cast<size_t>(p.host)].kf->points[static_cast<size_t>(p.pointIndex)].status !=
        PointStatus::active) {
      release[i] = 1;
      any = true;
    }
  }
  if (any) {
    removePointsIf(release);
  }
  for (size_t h = 0; h < m_frames.size(); ++h) {
    WindowFrame &wf = m_frames[h];
    for (size_t k = wf.scannedPoints; k < wf.kf->points.size(); ++k) {
      if (wf.kf->points[k].status == PointStatus::active) {
        registerPoint(static_cast<int>(h), static_cast<int>(k));
      }
    }
    wf.scannedPoints = wf.kf->points.size();
  }
  // Refresh the pointers into Keyframe::points (the vectors may have grown) and the inverse depths.
  m_anchoredPoints = 0;
  for (WindowPoint &p : m_points) {
    const MapPoint &mp = m_frames[static_cast<size_t>(p.host)].kf->points[static_cast<size_t>(p.pointIndex)];
    p.obs.u = mp.u;
    p.obs.v = mp.v;
    p.obs.idepth = mp.idepth;
    p.obs.patch = mp.patch.data();
    p.obs.weight = mp.patchWeight.data();
    p.obs.idepthPrior = mp.idepthPrior;
    p.obs.priorWeight = mp.idepthPriorWeight;
    p.anchor.active = m_anchors && mp.anchorKeyframeId >= 0;
    if (p.anchor.active) {
      p.anchor.anchorMw = mp.anchorCMw;
      p.anchor.u = mp.anchorU;
      p.anchor.v = mp.anchorV;
      p.anchor.idepth = mp.anchorIdepth;
      p.anchor.idepthWeight = mp.anchorIdepthWeight;
      p.anchor.pixelWeight = m_anchorPixelWeight;
      p.anchor.huberPx = m_anchorHuberPx;
      ++m_anchoredPoints;
    }
  }
  m_allPoints.resize(m_points.size());
  for (size_t i = 0; i < m_points.size(); ++i) {
    m_allPoints[i] = static_cast<int>(i);
  }
  if (m_hxp.size() < m_points.size() * kMaxWindowKeyframes) {
    m_hxp.resize(m_points.size() * kMaxWindowKeyframes);
  }
}

void WindowOptimizer::removePointsIf(const std::vector<char> &remove)
{
  size_t out = 0;
  for (size_t i = 0; i < m_points.size(); ++i) {
    if (!remove[i]) {
      if (out != i) {
        m_points[out] = std::move(m_points[i]);
      }
      ++out;
    }
  }
  m_points.resize(out);
  m_allPoints.resize(out);
  for (size_t i = 0; i < out; ++i) {
    m_allPoints[i] = static_cast<int>(i);
  }
}

void WindowOptimizer::prepareContext()
{
  const int n = static_cast<int>(m_frames.size());
  m_ctx.settings = m_settings;
  m_ctx.numFrames = n;
  for (int i = 0; i < n; ++i) {
    m_ctx.levels[i] = &m_frames[static_cast<size_t>(i)].kf->frame->pyramid.level(0);
    m_ctx.poses[i] = m_states[static_cast<size_t>(i)].cMw;
  }
  for (int h = 0; h < n; ++h) {
    const KeyframeState &sh = m_states[static_cast<size_t>(h)];
    const double eh = m_frames[static_cast<size_t>(h)].kf->frame->exposure;
    for (int t = 0; t < n; ++t) {
      if (t == h) {
        continue;
      }
      const KeyframeState &st = m_states[static_cast<size_t>(t)];
      m_ctx.pair(h, t).set(sh.cMw, sh.a, sh.b, eh, st.cMw, st.a, st.b,
                           m_frames[static_cast<size_t>(t)].kf->frame->exposure);
    }
  }
}

void WindowOptimizer::linearizeAll(const std::vector<int> &order, WindowAccumulator &acc)
{
  const int n = static_cast<int>(m_frames.size());
  acc.reset(n);
  if (m_pool->threads() == 0) {
    // Single range straight into acc: the same sums, in the same order, as before the pool existed.
    linearizeRange(m_ctx, m_points, order, 0, order.size(), m_hxp.data(), acc);
    return;
  }
  // Each participant writes only the points of its chunk and its own accumulator (WindowLinearization.h).
  m_pool->run(order.size(), [&](int w, size_t begin, size_t end) {
    WindowAccumulator &wa = m_workerAcc[static_cast<size_t>(w)];
    wa.reset(n);
    linearizeRange(m_ctx, m_points, order, begin, end, m_hxp.data(), wa);
  });
  // Fixed participant order (and fixed chunks for a given thread count): deterministic sums. Participants with an
  // empty chunk were not called, their accumulators may hold stale sums: skip them.
  for (int w = 0; w < m_pool->participants(); ++w) {
    size_t begin, end;
    WorkerPool::chunk(order.size(), m_pool->participants(), w, begin, end);
    if (begin < end) {
      acc.add(m_workerAcc[static_cast<size_t>(w)]);
    }
  }
}

void WindowOptimizer::schurAll(const std::vector<int> &order, double lambda, WindowAccumulator &acc)
{
  if (m_pool->threads() == 0) {
    schurRange(m_ctx, m_points, order, 0, order.size(), m_hxp.data(), lambda, acc);
    return;
  }
  const Eigen::Index dim = acc.Hsc.rows();
  m_pool->run(order.size(), [&](int w, size_t begin, size_t end) {
    WindowAccumulator &wa = m_workerAcc[static_cast<size_t>(w)];
    wa.Hsc.setZero(dim, dim);
    wa.bsc.setZero(dim);
    schurRange(m_ctx, m_points, order, begin, end, m_hxp.data(), lambda, wa);
  });
  for (int w = 0; w < m_pool->participants(); ++w) {
    size_t begin, end;
    WorkerPool::chunk(order.size(), m_pool->participants(), w, begin, end);
    if (begin < end) {
      acc.Hsc += m_workerAcc[static_cast<size_t>(w)].Hsc;
      acc.bsc += m_workerAcc[static_cast<size_t>(w)].bsc;
    }
  }
}

double WindowOptimizer::energyAll(const std::vector<int> &order)
{
  if (m_pool->threads() == 0) {
    return energyRange(m_ctx, m_points, order, 0, order.size());
  }
  std::fill(m_workerEnergy.begin(), m_workerEnergy.end(), 0.);
  m_pool->run(order.size(), [&](int w, size_t begin, size_t end) {
    m_workerEnergy[static_cast<size_t>(w)] = energyRange(m_ctx, m_points, order, begin, end);
  });
  double e = 0.;
  for (double we : m_workerEnergy) {
    e += we;
  }
  return e;
}

OptimizationSummary WindowOptimizer::optimize(int maxIterations)
{
  const auto t0 = std::chrono::steady_clock::now();
  OptimizationSummary summary;
  syncStatesAndPoints();
  summary.activePoints = static_cast<int>(m_points.size());
  if (m_frames.size() < 2 || m_points.empty()) {
    summary.totalMs = elapsedMs(t0);
    return summary;
  }
  prepareContext();
  linearizeAll(m_allPoints, m_acc);
  // Affine priors (DSO) and the marginalisation prior enter the frame system directly.

  assembleFullSystem(m_acc, m_H, m_b);
  addPriors(m_H, m_b);

  double energy = m_acc.energy + priorEnergy();
  summary.initialEnergy = energy;
  double lambda = m_mapper.initialLambda;
  Eigen::VectorXd dx;
  for (int it = 0; it < maxIterations; ++it) {
    ++summary.iterations;
    if (!solveStep(lambda, dx)) {
      lambda *= kLambdaRejectFactor;
      if (lambda > kMaxLambda) {
        break;
      }
      continue;
    }
    const double norm = stepNorm(dx);
    backupStates();
    applyStep(dx, lambda);
    prepareContext();
    // The step is judged by the energy of the linearisation at the new state (the same sums, in the same order, as
    // energyAll()): most steps are accepted, and the linearisation is then the next iteration's (DSO does the
    // same). A rejected step pays one linearisation more, at the restored state.
    linearizeAll(m_allPoints, m_acc);
    const double newEnergy = m_acc.energy + priorEnergy();
    if (newEnergy < energy) {
      energy = newEnergy;
      summary.acceptedEnergies.push_back(energy);
      ++summary.acceptedSteps;
      lambda *= kLambdaAcceptFactor;
      assembleFullSystem(m_acc, m_H, m_b);
      addPriors(m_H, m_b);
      summary.converged = norm < m_mapper.stepConvergenceThreshold;
    } else {
      restoreStates();
      prepareContext();
      linearizeAll(m_allPoints, m_acc);
      lambda *= kLambdaRejectFactor;
      // A rejected step that small is numerical noise around the minimum.
      summary.converged = norm < m_mapper.stepConvergenceThreshold;
    }
    if ((summary.converged && summary.iterations >= m_mapper.minOptimizationIterations) || lambda > kMaxLambda) {
      break;
    }
  }
  summary.finalEnergy = energy;
  summary.finalPhotometricEnergy = m_acc.energy; // m_acc is the linearisation at the final state
  summary.finalLambda = lambda;
  summary.inlierResiduals = m_acc.inliers;
  finalizeOutliers(summary);
  writeBack();
  m_accCurrent = true; // m_acc holds the linearisation at the final states (pairInformation() re-uses it)
  summary.totalMs = elapsedMs(t0);
  summary.msPerIteration = summary.iterations > 0 ? summary.totalMs / summary.iterations : 0.;
  return summary;
}

void WindowOptimizer::finalizeOutliers(OptimizationSummary &summary)
{
  // m_points' residual states are those of the last linearisation, i.e. of the final state (DSO removes the
  // residuals found outliers there for good).
  std::vector<char> remove(m_points.size(), 0);
  bool any = false;
  for (size_t i = 0; i < m_points.size(); ++i) {
    WindowPoint &p = m_points[i];
    const size_t before = p.residuals.size();
    p.residuals.erase(std::remove_if(p.residuals.begin(), p.residuals.end(),
                                     [](const WindowResidual &r) { return r.state == ResidualState::outlier; }),
                      p.residuals.end());
    const int removed = static_cast<int>(before - p.residuals.size());
    p.outlierResidualsRemoved += removed;
    summary.removedResiduals += removed;
    const int seen = p.outlierResidualsRemoved + p.inlierResiduals;
    if (p.outlierResidualsRemoved > 0 && (p.residuals.empty() || static_cast<double>(p.outlierResidualsRemoved) >
                                                                     m_mapper.outlierResidualFraction * seen)) {
      MapPoint &mp = m_frames[static_cast<size_t>(p.host)].kf->points[static_cast<size_t>(p.pointIndex)];
      mp.status = PointStatus::outlier;
      remove[i] = 1;
      any = true;
      ++summary.outlierPoints;
    }
  }
  if (any) {
    // Write the flagged points' last estimate before they leave.
    writeBack();
    removePointsIf(remove);
  }
}

void WindowOptimizer::writeBack()
{
  for (size_t i = 0; i < m_frames.size(); ++i) {
    Frame &f = *m_frames[i].kf->frame;
    f.cMw = m_states[i].cMw;
    f.affine.a = m_states[i].a;
    f.affine.b = m_states[i].b;
  }
  for (const WindowPoint &p : m_points) {
    MapPoint &mp = m_frames[static_cast<size_t>(p.host)].kf->points[static_cast<size_t>(p.pointIndex)];
    mp.idepth = p.obs.idepth;
    // DSO's variance proxy: the inverse of the point's own (undamped) Hessian block.
    mp.idepthVar = p.Hpp > 0. ? 1. / p.Hpp : std::numeric_limits<double>::infinity();
    if (mp.depthFromPrior && p.Hpp - p.obs.priorWeight >= m_mapper.minIdepthHessianActivate) {
      forgetDepthGuess(mp); // the window measures its depth now, as it would to activate it
    }
    // Co-visibility: every keyframe in which the point had an inlier residual observes it.
    for (const WindowResidual &r : p.residuals) {
      if (r.state == ResidualState::inlier) {
        addObserver(mp.observers, m_frames[static_cast<size_t>(r.target)].kf->id());
      }
    }
  }
}
} // namespace hslam
