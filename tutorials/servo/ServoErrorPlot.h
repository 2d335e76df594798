// A picture of a servo run: pose error to the goal and SLAM error over time, drawn without a display.
#ifndef HSLAM_TUTORIAL_SERVO_ERROR_PLOT_H
#define HSLAM_TUTORIAL_SERVO_ERROR_PLOT_H

#include "servo/HSlamServoSimulation.h"

#include <visp3/core/vpImage.h>
#include <visp3/core/vpRGBa.h>

#include <string>
#include <vector>

namespace hslam_servo
{
/*!
  Two panels over time (seconds): translation error (metres) and rotation error (degrees), log scale, each with the
  true servo error (camera to goal) and the SLAM error (SLAM pose vs simulator pose). A vertical line marks the end
  of the initialisation path. vpPlot needs a display; this draws into an image that vpImageIo writes as PNG.
  \param I : resized to \e width x \e height.
*/
void drawServoErrors(vpImage<vpRGBa> &I, const std::vector<ServoSample> &samples, const std::string &caption,
                     unsigned int width = 1000, unsigned int height = 760);
} // namespace hslam_servo

#endif
