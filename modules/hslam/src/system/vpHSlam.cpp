/*
 * H-SLAM for ViSP.
 */
#include <visp3/hslam/vpHSlam.h>

#include "system/SlamSystem.h"

#include <visp3/hslam/vpHSlamException.h>

vpHSlam::vpHSlam(const vpHSlamCamera &camera, const vpHSlamParameters &parameters,
                 const vpHSlamPhotometricCalibration &photometric)
    : m_system(new hslam::SlamSystem(camera, parameters, photometric))
{
}

vpHSlam::vpHSlam(const vpHSlamImageSource &source, const vpHSlamParameters &parameters)
    : m_system(new hslam::SlamSystem(source.getCamera(), parameters,
                                     parameters.system.usePhotometricCalibration ? source.getPhotometricCalibration()
                                                                                 : vpHSlamPhotometricCalibration()))
{
}

vpHSlam::~vpHSlam() = default;

vpHSlam::State vpHSlam::track(const vpImage<unsigned char> &I, double timestamp, double exposure)
{
  return m_system->track(I, timestamp, exposure);
}

vpHSlam::State vpHSlam::getState() const
{
  return m_system->state();
}

vpHomogeneousMatrix vpHSlam::get_cMw() const
{
  return m_system->get_cMw();
}

bool vpHSlam::hasPose() const
{
  return m_system->hasPose();
}

std::vector<vpHSlam::Keyframe> vpHSlam::getKeyframes() const
{
  return m_system->keyframes();
}

std::vector<vpColVector> vpHSlam::getActivePoints(std::vector<double> *depths) const
{
  return m_system->activePoints(depths);
}

std::vector<vpImagePoint> vpHSlam::getDescriptorMatches() const
{
  return m_system->descriptorMatches();
}

std::vector<vpHSlam::MapPoint> vpHSlam::getMapPoints() const
{
  return m_system->mapPoints();
}

std::vector<vpHSlam::GraphEdge> vpHSlam::getGraphEdges() const
{
  return m_system->graphEdges();
}

void vpHSlam::saveMap(const std::string &path)
{
  m_system->saveMap(path);
}

void vpHSlam::loadMap(const std::string &path)
{
  m_system->loadMap(path);
}

vpHSlamTrajectory vpHSlam::getTrajectory(int segment) const
{
  return m_system->trajectory(segment);
}

vpHSlamTrajectory vpHSlam::getKeyframeTrajectory(int segment) const
{
  return m_system->keyframeTrajectory(segment);
}

std::vector<unsigned int> vpHSlam::getTrajectorySegments() const
{
  return m_system->trajectorySegments();
}

vpHSlam::Statistics vpHSlam::getStatistics() const
{
  return m_system->statistics();
}

void vpHSlam::synchronize()
{
  m_system->finishBackgroundWork();
}

void vpHSlam::reset()
{
  m_system->reset();
}

vpCameraParameters vpHSlam::getCameraParameters() const
{
  return m_system->preprocessor().getCameraParameters();
}

unsigned int vpHSlam::getWidth() const
{
  return static_cast<unsigned int>(m_system->preprocessor().width());
}

unsigned int vpHSlam::getHeight() const
{
  return static_cast<unsigned int>(m_system->preprocessor().height());
}

void vpHSlam::getRectifiedImage(vpImage<unsigned char> &I) const
{
  m_system->rectifiedImage(I);
}

const vpHSlamParameters &vpHSlam::getParameters() const
{
  return m_system->parameters();
}

void vpHSlam::setTag(const vpHSlamTag &tag)
{
  m_system->setTag(tag);
}

vpHSlamTag vpHSlam::getTag() const
{
  return m_system->tag();
}

bool vpHSlam::isMetric() const
{
  return m_system->worldFrame().metric;
}

vpHSlam::WorldFrame vpHSlam::getWorldFrame() const
{
  return m_system->worldFrame();
}

std::string vpHSlam::stateName(State state)
{
  switch (state) {
  case stateInitializing:
    return "initializing";
  case stateTracking:
    return "tracking";
  case stateLost:
    return "lost";
  }
  return "unknown";
}
