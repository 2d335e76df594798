/*
 * H-SLAM for ViSP.
 */
/*!
  \file AffineBrightness.h
  \brief Per-frame affine brightness (a, b) and the host-to-target brightness transfer (DSO's photometric model).

  Model (DSO, Engel et al. 2016, eq. 4): a pixel of irradiance B seen in frame i with exposure t_i has
  intensity I_i = t_i e^{a_i} B + b_i. Comparing host i and target j:
      I_j[p'] - b_j  =  (t_j e^{a_j}) / (t_i e^{a_i}) (I_i[p] - b_i),
  i.e. I_j[p'] = a_ji I_i[p] + b_ji with a_ji = t_j e^{a_j} / (t_i e^{a_i}) and b_ji = b_j - a_ji b_i.
  With a photometric calibration the exposures t are known; without one t = 1 and (a, b) absorb the changes
  (estimated with a weak prior, DSO "mode 1").
*/
#ifndef HSLAM_MAP_AFFINE_BRIGHTNESS_H
#define HSLAM_MAP_AFFINE_BRIGHTNESS_H

#include <cmath>

namespace hslam
{
//! Brightness parameters of one frame: I = t e^a B + b.
struct AffineBrightness {
  double a = 0.; //!< log gain
  double b = 0.; //!< offset, intensity units

  //! (a_ji, b_ji) mapping host intensities to target intensities, see the file comment.
  static void transfer(double exposureHost, const AffineBrightness &host, double exposureTarget,
                       const AffineBrightness &target, double &aji, double &bji)
  {
    aji = (exposureTarget * std::exp(target.a)) / (exposureHost * std::exp(host.a));
    bji = target.b - aji * host.b;
  }
};
} // namespace hslam

#endif
