/*
 * H-SLAM for ViSP.
 */
/*!
  \file vpHSlamLiveView.h
  \brief Composes what a person watching H-SLAM wants to see into one colour image: the camera image with the
  active points, a status line, and a top view of trajectory and keyframes.
*/
#ifndef VP_HSLAM_LIVE_VIEW_H
#define VP_HSLAM_LIVE_VIEW_H

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>
#include <visp3/core/vpRGBa.h>

#include <string>

class vpHSlam;

/*!
  \class vpHSlamLiveView
  \ingroup group_hslam
  \brief Draws the state of a vpHSlam into a vpImage<vpRGBa>, for a window (vpDisplayX, vpDisplayOpenCV, ...) or a
  screenshot.

  Left: the last rectified image, with the points active in the window projected by the current pose and coloured
  by inverse depth (near red, through yellow and green, far blue; the scale spans the 5th to 95th percentile of the
  visible points), the keypoints the last frame matched by ORB descriptor (vpHSlam::getDescriptorMatches(), hybrid
  and indirect tracking) as small magenta crosses, and a status line (frame, state, frame rate, active points,
  keyframes, in magenta "+ orb N" with the number of those matches unless tracking is direct (adaptive tracking: only
  for a frame that used them, "direct" in white otherwise), with a tag (vpHSlam::setTag()) in yellow "metric" or
  "tag N" (its sightings so far), and an optional hint such as the keys of the program). Once the outputs are metric,
  the tag's black square as the system places it (yellow; tag frame only) and the output frame's axes at its origin,
  one tag size long (x red, y green, z blue), are drawn over the image.
  Right: a top view of the world (x right, z up in the picture) with the trajectory of every tracked frame (green), the
  keyframes (blue squares, filled while in the optimisation window) and the current camera with its viewing direction
  (red).

  Drawing only: no window is opened here, so the same code serves live programs, tests (an off-screen image) and
  pictures. The canvas is resized to (image width + getTopViewWidth()) x image height.

  Threading: draw() reads the system through its const, thread-safe getters; call it from the thread that calls
  vpHSlam::track().

  \code
  vpHSlamLiveView view;
  vpImage<vpRGBa> canvas;
  vpDisplayX window;
  while (source->acquire(I, frame)) {
    slam.track(I, frame.timestamp);
    view.draw(slam, frame.index, fps, canvas, "space: pause  q: quit");
    if (frame.index == 0) window.init(canvas);
    vpDisplay::display(canvas);
    vpDisplay::flush(canvas);
  }
  \endcode
*/
class VISP_EXPORT vpHSlamLiveView
{
public:
  vpHSlamLiveView();

  /*!
    Draw the current state.
    \param slam : the system (after track()).
    \param frameIndex : index of the last frame, shown in the status line.
    \param fps : measured frame rate, Hz (<= 0: not shown).
    \param canvas : resized and overwritten.
    \param hint : optional text appended to the status line (e.g. the program's keys).
  */
  void draw(const vpHSlam &slam, unsigned int frameIndex, double fps, vpImage<vpRGBa> &canvas,
            const std::string &hint = "") const;

  //! Width of the top-view panel, pixels (its height is the image height).
  unsigned int getTopViewWidth() const { return m_topViewWidth; }
  //! Set the width of the top-view panel, pixels (at least 64; 0 hides the panel).
  void setTopViewWidth(unsigned int width);

  //! Colour of a normalised inverse depth in [0, 1] (0 far, blue; 1 near, red), as drawn on the points.
  static vpRGBa inverseDepthColor(double x);

private:
  unsigned int m_topViewWidth;
};

#endif
