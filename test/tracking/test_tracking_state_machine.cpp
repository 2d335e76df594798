// The tracking state machine's transition table (TrackingStateMachine.h): every row, pairs outside it leave the phase
// unchanged, and a machine driven through a segment without a tracking reference.
#include "tracking/TrackingStateMachine.h"

#include <gtest/gtest.h>

#include <memory>

using namespace hslam;

namespace
{
using Phase = TrackingStateMachine::Phase;
using Event = TrackingStateMachine::Event;

//! A map with nothing in it: the machine never reads it when the frame tracker has no reference.
class EmptyMap : public TrackingMap
{
public:
  SE3d keyframePose(int) const override { return SE3d(); }
  bool framePose(int, SE3d &) const override { return false; }
  void waitForMapping() override {}
  bool indexesKeyframes() const override { return false; }
  std::vector<RelocalizationKeyframe> relocalizationCandidates(RelocalizationFrame &, int, int) override { return {}; }
  std::vector<WindowView> windowViews() override { return {}; }
  void localMapFeatures(int, std::vector<ReferenceFeature> &, std::vector<int> &) override {}
  void localMapReference(const std::vector<int> &, const SE3d &, std::vector<CoarseTrackerPoint> &) override {}
  int closestKeyframe(const SE3d &, const std::vector<int> &) override { return -1; }
};
} // namespace

TEST(TrackingStateMachine, TransitionTableRows)
{
  EXPECT_EQ(TrackingStateMachine::next(Phase::newSegment, Event::initialized), Phase::tracking);
  EXPECT_EQ(TrackingStateMachine::next(Phase::tracking, Event::aligned), Phase::tracking);
  EXPECT_EQ(TrackingStateMachine::next(Phase::tracking, Event::failed), Phase::tracking);
  EXPECT_EQ(TrackingStateMachine::next(Phase::tracking, Event::failedTooOften), Phase::relocalizing);
  EXPECT_EQ(TrackingStateMachine::next(Phase::tracking, Event::failedForGood), Phase::lost);
  EXPECT_EQ(TrackingStateMachine::next(Phase::tracking, Event::noReference), Phase::lost);
  EXPECT_EQ(TrackingStateMachine::next(Phase::relocalizing, Event::noReference), Phase::lost);
  EXPECT_EQ(TrackingStateMachine::next(Phase::relocalizing, Event::refused), Phase::relocalizing);
  EXPECT_EQ(TrackingStateMachine::next(Phase::relocalizing, Event::timedOut), Phase::lost);
  EXPECT_EQ(TrackingStateMachine::next(Phase::relocalizing, Event::relocalized), Phase::tracking);
  EXPECT_EQ(TrackingStateMachine::next(Phase::relocalizing, Event::relocalizedMoving), Phase::continuedMotion);
  EXPECT_EQ(TrackingStateMachine::next(Phase::continuedMotion, Event::aligned), Phase::continuedMotion);
  EXPECT_EQ(TrackingStateMachine::next(Phase::continuedMotion, Event::failedForGood), Phase::lost);
  EXPECT_EQ(TrackingStateMachine::next(Phase::continuedMotion, Event::motionUsed), Phase::tracking);
  for (Phase from : {Phase::newSegment, Phase::tracking, Phase::relocalizing, Phase::continuedMotion, Phase::lost}) {
    EXPECT_EQ(TrackingStateMachine::next(from, Event::segmentEnded), Phase::newSegment);
  }
}

TEST(TrackingStateMachine, PairsOutsideTheTableKeepThePhase)
{
  EXPECT_EQ(TrackingStateMachine::next(Phase::tracking, Event::initialized), Phase::tracking);
  EXPECT_EQ(TrackingStateMachine::next(Phase::tracking, Event::timedOut), Phase::tracking);
  EXPECT_EQ(TrackingStateMachine::next(Phase::tracking, Event::motionUsed), Phase::tracking);
  EXPECT_EQ(TrackingStateMachine::next(Phase::newSegment, Event::noReference), Phase::newSegment);
  EXPECT_EQ(TrackingStateMachine::next(Phase::relocalizing, Event::failedTooOften), Phase::relocalizing);
  EXPECT_EQ(TrackingStateMachine::next(Phase::lost, Event::relocalized), Phase::lost);
}

TEST(TrackingStateMachine, NoReferenceEndsTheSegment)
{
  const vpHSlamParameters params;
  FrameTracker frames(params, false, 640, 480, nullptr);
  EmptyMap map;
  TrackingStateMachine machine(params, frames, nullptr, map, false, false);
  EXPECT_EQ(machine.phase(), Phase::newSegment);
  machine.startSegment(1, 0);
  EXPECT_EQ(machine.phase(), Phase::tracking);
  const TrackingStateMachine::Outcome out = machine.track(std::make_shared<Frame>());
  EXPECT_EQ(out.report, TrackingStateMachine::Outcome::endSegment);
  EXPECT_EQ(machine.phase(), Phase::lost);
  machine.endSegment();
  EXPECT_EQ(machine.phase(), Phase::newSegment);
}
