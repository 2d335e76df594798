// The tracking state machine's transition table (TrackingStateMachine.h): every row, pairs outside it leave the phase
// unchanged, and a machine driven through a segment without a tracking reference.
#include "tracking/TrackingStateMachine.h"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

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

//! A row of a transition table: from, event, expected next phase.
struct Row {
  Phase from;
  Event event;
  Phase to;
};

void expectRows(const std::vector<Row> &rows)
{
  for (const Row &r : rows) {
    EXPECT_EQ(TrackingStateMachine::next(r.from, r.event), r.to)
        << "from " << static_cast<int>(r.from) << " on event " << static_cast<int>(r.event);
  }
}
} // namespace

TEST(TrackingStateMachine, TransitionTableRows)
{
  expectRows({{Phase::newSegment, Event::initialized, Phase::tracking},
              {Phase::tracking, Event::aligned, Phase::tracking},
              {Phase::tracking, Event::failed, Phase::tracking},
              {Phase::tracking, Event::failedTooOften, Phase::relocalizing},
              {Phase::tracking, Event::failedForGood, Phase::lost},
              {Phase::tracking, Event::noReference, Phase::lost},
              {Phase::relocalizing, Event::noReference, Phase::lost},
              {Phase::relocalizing, Event::refused, Phase::relocalizing},
              {Phase::relocalizing, Event::timedOut, Phase::lost},
              {Phase::relocalizing, Event::relocalized, Phase::tracking},
              {Phase::relocalizing, Event::relocalizedMoving, Phase::continuedMotion},
              {Phase::continuedMotion, Event::aligned, Phase::continuedMotion},
              {Phase::continuedMotion, Event::failedForGood, Phase::lost},
              {Phase::continuedMotion, Event::motionUsed, Phase::tracking}});
  for (Phase from : {Phase::newSegment, Phase::tracking, Phase::relocalizing, Phase::continuedMotion, Phase::lost}) {
    EXPECT_EQ(TrackingStateMachine::next(from, Event::segmentEnded), Phase::newSegment);
  }
}

TEST(TrackingStateMachine, PairsOutsideTheTableKeepThePhase)
{
  expectRows({{Phase::tracking, Event::initialized, Phase::tracking},
              {Phase::tracking, Event::timedOut, Phase::tracking},
              {Phase::tracking, Event::motionUsed, Phase::tracking},
              {Phase::newSegment, Event::noReference, Phase::newSegment},
              {Phase::relocalizing, Event::failedTooOften, Phase::relocalizing},
              {Phase::lost, Event::relocalized, Phase::lost}});
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
