// Pose-based visual servoing of a simulated free-flying camera whose pose is measured by H-SLAM on rendered images.
// Used by tutorial-hslam-servo; lives beside it (not in the module) because it needs ViSP's visp_vs and
// visp_visual_features, which the module does not depend on.
#ifndef HSLAM_TUTORIAL_SERVO_SIMULATION_H
#define HSLAM_TUTORIAL_SERVO_SIMULATION_H

#include <visp3/core/vpColVector.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpImage.h>
#include <visp3/hslam/vpHSlam.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <functional>
#include <string>
#include <vector>

namespace hslam_servo
{
/*!
  Every setting of the simulation, with its default. The defaults are those of tutorial-hslam-servo; its test runs
  them on 480x360 images.
*/
struct ServoSettings {
  unsigned int width = 640;   //!< rendered image width, pixels (focal length 500 px at 640, see vpHSlamSyntheticScene)
  unsigned int height = 480;  //!< rendered image height, pixels
  double fps = 30.;           //!< simulated frame rate: one servo iteration and one image per 1 / fps seconds
  unsigned int sceneSeed = 1; //!< synthetic scene seed: the start pose is frame 0 of its camera loop
  double noiseSigma = 0.;     //!< image noise, grey levels (standard deviation)
  std::string imagesDataPath; //!< ViSP image data for the textures; empty: vpHSlamSyntheticScene's default

  //! Initialisation path: a semicircle in the camera's x-y plane (no rotation), this many frames long.
  unsigned int initFrames = 45;
  double initRadiusMetres = 0.12; //!< radius of that semicircle: the camera ends 2 x radius below its start

  /*!
    Tag mode (tutorial-hslam-servo --tag SIZE): > 0 hangs a tag36h11 whose black square is this many metres on the
    wall the start camera faces, and the SLAM's metric frame from it (vpHSlam::setTag, docs/metric-tag-frame.md)
    replaces the semicircle's Sim(3): the SLAM pose is used as it comes, in metres in the tag's frame, and the goal is
    given in that frame (tMcd). The camera still follows the initialisation path (a monocular map needs the motion),
    but its known poses are not used. 0 (default): the semicircle mode.
  */
  double tagSize = 0.;
  int tagId = 0;                     //!< tag mode: the tag's id (its frame is the world's)
  vpImage<unsigned char> tagPicture; //!< tag mode: the tag as printed (tutorials/servo/TagPicture.h)
  unsigned int tagBlackCells = 0;    //!< tag mode: cells its black square spans
  bool goalInTagFrame = false;       //!< tag mode: tMcd is the goal; false: c0Mcd's goal, expressed in the tag
  vpHomogeneousMatrix tMcd;          //!< tag mode: desired camera pose in the tag's frame (goalInTagFrame)

  //! Desired camera pose, expressed in the camera frame at the very start (before the initialisation path).
  vpHomogeneousMatrix c0Mcd = vpHomogeneousMatrix(0.25, -0.05, 0.30, 0., vpMath::rad(-12.), vpMath::rad(4.));

  // Control law: adaptive gain lambda(x) = (l0 - linf) exp(-l0' x / (l0 - linf)) + linf, x = |e|_inf (ViSP's
  // vpAdaptiveGain, as in its PBVS tutorials): slow and smooth far from the goal, fast near it. Far from it the
  // speed bounds below act anyway (0.8/s on 0.5 m asks for 0.4 m/s); near it the time constant 1 / l0 is 0.25 s
  // (7.5 frames), and l0 dt = 0.13 keeps the sampled loop far from its stability limit (l0 dt < 2) and free of
  // overshoot, so the SLAM's sub-millimetre noise is not amplified.
  double gainAtZero = 4.;       //!< l0, 1/s
  double gainAtInfinity = 0.8;  //!< linf, 1/s
  double gainSlopeAtZero = 30.; //!< l0', 1/s per unit of error
  //! Motion per frame is bounded (whole twist scaled, so the direction is kept): direct tracking needs small
  //! inter-frame motion. Half the synthetic sequences' bounds (2 cm and 1 degree): 0.3 m/s and 15 degree/s at 30 Hz.
  double maxStepMetres = 0.01;
  double maxStepDegrees = 0.5; //!< rotation bound per frame, degrees

  unsigned int maxIterations = 600;    //!< servo iterations before giving up
  double convergedMetres = 5e-4;       //!< converged: SLAM-measured translation error below this (metres) ...
  double convergedDegrees = 0.05;      //!< ... and rotation error below this (degrees) ...
  unsigned int convergedFrames = 10;   //!< ... for this many frames in a row
  unsigned int maxUntrackedFrames = 3; //!< servoing stops (failure) after this many frames without a SLAM pose

  vpHSlamParameters slam = deterministicParameters(); //!< settings of the SLAM system

  /*!
    Defaults with mapping in the caller's thread (the closed loop is then reproducible run to run) and direct
    tracking: near the goal the camera barely moves, and the ORB keypoints of hybrid tracking sit on integer pixels
    (FAST), which made the converged pose jitter by 0.5-1 mm where the sub-pixel direct alignment holds 0.4 mm
    (measured on the noisy-image test: 516 iterations instead of about 140 to meet the stop rule). A --config file
    can ask for hybrid tracking.
  */
  static vpHSlamParameters deterministicParameters()
  {
    vpHSlamParameters params;
    params.system.deterministic = true;
    params.tracking.mode = vpHSlamParameters::trackingDirect;
    return params;
  }
};

//! What happened at one frame (one image rendered, tracked, and one velocity applied).
struct ServoSample {
  unsigned int frame = 0;                            //!< frame index since the start
  double time = 0.;                                  //!< seconds since the start
  bool servoing = false;                             //!< false on the initialisation path
  vpHSlam::State state = vpHSlam::stateInitializing; //!< SLAM state for this frame
  bool hasEstimate = false;          //!< a SLAM pose in the simulator's world frame exists (after the Sim(3) alignment)
  double servoErrorMetres = 0.;      //!< ground truth: |translation| of cdMc
  double servoErrorDegrees = 0.;     //!< ground truth: rotation angle of cdMc
  double measuredErrorMetres = 0.;   //!< the same from the SLAM pose (what the servo sees); 0 without estimate
  double measuredErrorDegrees = 0.;  //!< rotation of the same
  double slamErrorMetres = 0.;       //!< distance between SLAM and true camera centres (when hasEstimate)
  double slamErrorDegrees = 0.;      //!< angle between SLAM and true orientations (when hasEstimate)
  double speedMetresPerSecond = 0.;  //!< commanded translation speed
  double speedDegreesPerSecond = 0.; //!< commanded rotation speed
};

//! Outcome of a run.
struct ServoResult {
  bool initialised = false;         //!< SLAM had a map and the Sim(3) alignment (tag mode: the metric frame) was there
  bool tagMode = false;             //!< the scale and frame came from the tag (ServoSettings::tagSize)
  vpHomogeneousMatrix tMcd;         //!< tag mode: the goal in the tag's frame
  bool converged = false;           //!< the convergence test of ServoSettings passed
  std::string failure;              //!< why not, when not
  unsigned int iterations = 0;      //!< servo iterations run (up to the first converged frame of the final streak)
  unsigned int frames = 0;          //!< frames rendered in all (initialisation + servo)
  double alignmentScale = 0.;       //!< Sim(3) scale: metres per SLAM unit (tag mode: the metric frame's)
  double alignmentRmseMetres = 0.;  //!< residual of the alignment over the initialisation path (tag mode: of the
                                    //!< tag's sightings), metres
  unsigned int alignmentPoses = 0;  //!< poses used for the alignment (tag mode: tag sightings kept)
  double slamSeconds = 0.;          //!< CPU time in vpHSlam::track(), seconds (wall clock)
  double renderSeconds = 0.;        //!< time spent rendering, seconds (wall clock)
  std::vector<ServoSample> samples; //!< one per frame
};

/*!
  Run the simulation: see tutorial-hslam-servo --help for the method. \e onSample is called once per frame, after
  the velocity for that frame is chosen. Initialisation frames get their SLAM error only in ServoResult::samples,
  filled in once the Sim(3) alignment is known. Throws vpException on bad settings or a missing texture folder.
*/
ServoResult runServo(const ServoSettings &settings, const std::function<void(const ServoSample &)> &onSample);
} // namespace hslam_servo

#endif
