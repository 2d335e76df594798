/*
 * H-SLAM for ViSP.
 */
/*!
  \file vpHSlamSyntheticScene.h
  \brief Synthetic image sequences of a textured room with exact ground truth.
*/
#ifndef VP_HSLAM_SYNTHETIC_SCENE_H
#define VP_HSLAM_SYNTHETIC_SCENE_H

#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpColVector.h>
#include <visp3/core/vpConfig.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpImage.h>

#include <memory>
#include <string>
#include <vector>

namespace hslam
{
class SyntheticRenderer;
class SyntheticTrajectory;
struct SimPicture;
} // namespace hslam

/*!
  \class vpHSlamSyntheticScene
  \ingroup group_hslam
  \brief Renders a monocular sequence of a closed, textured room along a smooth closed camera loop, with exact
  ground truth (poses, intrinsics, 3D point behind every pixel, photometric calibration).

  What it is for: tests and demonstrations that need a sequence whose every number is known. The room (5 x 2.6 x
  5.5 m, three boxes inside for parallax) is textured with real photographs from ViSP's image data (Debian
  package visp-images-data, found through vpIoTools::getViSPImagesDataPath() or
  /usr/share/visp-images-data/ViSP-images). Images are ray-cast with mip-mapped bilinear texture look-up and 2x2
  supersampling. The camera follows a hand-held-like path (sums of sinusoids in position and in small rotations)
  whose last frame has exactly the pose of the first, so loop closure can be tested; the motion between two
  frames stays below 2 cm and 1 degree whatever the frame count (amplitudes shrink for short sequences).

  Optional effects follow the TUM monoVO photometric model I = G(t V B): vignette V (written as vignette.png),
  camera response G (its inverse written as pcalib.txt), smoothly changing exposure t (written in times.txt),
  Gaussian noise in grey levels, and motion blur (mean of sub-frame renders over the exposure time, centred on
  the frame's pose).

  writeSequence() produces the TUM RGB-D layout used by the project's readers: rgb/NNNNNN.png (8-bit grey),
  rgb.txt, groundtruth.txt (camera-to-world wMc, TUM format, timestamps index / fps), camera.txt (DSO format,
  pinhole, absolute intrinsics), camera.xml (ViSP), times.txt (id, time in s, exposure in ms), and with the
  photometric effects vignette.png (8-bit) and pcalib.txt. The output is deterministic: a given configuration and
  seed give byte-identical files (std::mt19937 seeded explicitly, no time-dependent value).

  Threading: configure() is not thread-safe; after it, all const methods may run concurrently. The object owns its
  textures (a few tens of MB).

  \code
  vpHSlamSyntheticScene scene;
  vpHSlamSyntheticScene::Effects effects;
  effects.vignette = true;
  scene.configure(640, 480, 300, 30.0, 42, effects);
  vpImage<unsigned char> I;
  scene.render(0, I);
  vpHomogeneousMatrix wMc = scene.getPose(0);
  scene.writeSequence("/tmp/synthetic");
  \endcode
*/
class VISP_EXPORT vpHSlamSyntheticScene
{
public:
  //! Photometric and image-formation effects; all off by default (irradiance written as is).
  struct Effects {
    // A constructor rather than member initialisers: the struct is a default argument of configure().
    Effects() : vignette(false), response(false), exposureChanges(false), noiseSigma(0.0), motionBlur(false) {}
    bool vignette;        //!< radial fall-off to 50 % in the corners, written as vignette.png
    bool response;        //!< gamma-like camera response, its inverse written as pcalib.txt
    bool exposureChanges; //!< exposure varies smoothly (x0.625 .. x1.6 of 10 ms), written in times.txt
    double noiseSigma;    //!< standard deviation of additive Gaussian noise, grey levels
    bool motionBlur;      //!< average of sub-frame renders over the exposure time
  };

  //! Nothing rendered yet; call configure() before anything else.
  vpHSlamSyntheticScene();
  ~vpHSlamSyntheticScene();
  vpHSlamSyntheticScene(const vpHSlamSyntheticScene &) = delete;
  vpHSlamSyntheticScene &operator=(const vpHSlamSyntheticScene &) = delete;

  /*!
    Folder holding ViSP's image data ("ViSP-images"); empty (default) means vpIoTools::getViSPImagesDataPath(),
    then /usr/share/visp-images-data/ViSP-images. Takes effect at the next configure().
  */
  void setImagesDataPath(const std::string &path) { m_imagesDataPath = path; }

  /*!
    Times the camera drives the loop (default 1). With laps > 1 every lap revisits the same poses, which is what
    map re-use and loop closure need to be measured; laps should divide frames - 1 for every lap to start exactly
    at the pose of frame 0. Takes effect at the next configure().
    \exception vpHSlamException::invalidArgument for 0.
  */
  void setLaps(unsigned int laps);
  unsigned int getLaps() const { return m_laps; } //!< laps of the loop

  /*!
    false (default): the camera pans across the front wall as it goes round; true: it looks away from the centre of
    its loop and turns a full circle per lap, filming the four walls in turn (what it saw first leaves the view, as
    in a walk round a building). A lap must then take at least 400 frames (0.9 degree per frame at most); configure()
    throws otherwise. Takes effect at the next configure().
  */
  void setLookOutward(bool outward) { m_lookOutward = outward; }
  bool getLookOutward() const { return m_lookOutward; } //!< see setLookOutward()

  /*!
    Set up the scene, camera and trajectory (loads the textures on first call or when the path changed).
    \param width, height : image size, pixels (>= 16 each). The focal length scales with the width (500 px at 640).
    \param frames : frame count (>= 2); frame frames - 1 has the pose of frame 0.
    \param fps : frame rate (> 0), for timestamps, exposure and motion blur.
    \param seed : selects the trajectory's phases and the noise.
    \param effects : photometric effects.
    \exception vpHSlamException::invalidArgument for out-of-range values, vpHSlamException::fileNotFound naming the
    folder when no texture photograph is found.
  */
  void configure(unsigned int width = 640, unsigned int height = 480, unsigned int frames = 300, double fps = 30.0,
                 unsigned int seed = 1, const Effects &effects = Effects());

  unsigned int getWidth() const { return m_width; }       //!< pixels
  unsigned int getHeight() const { return m_height; }     //!< pixels
  unsigned int getFrameCount() const { return m_frames; } //!< frames
  double getFrameRate() const { return m_fps; }           //!< frames per second
  const Effects &getEffects() const { return m_effects; } //!< effects in use

  //! Pinhole intrinsics of the rendered images (no distortion; (0,0) is the centre of the top-left pixel).
  vpCameraParameters getCameraParameters() const;
  //! Camera-to-world pose of frame i (world: x right, y down towards the floor, z forward; metres).
  vpHomogeneousMatrix getPose(unsigned int i) const;
  //! Timestamp of frame i, seconds (i / fps).
  double getTimestamp(unsigned int i) const;
  //! Exposure time of frame i, milliseconds.
  double getExposure(unsigned int i) const;
  //! The inverse response G^-1 as written to pcalib.txt (256 values, identity when the response is off).
  std::vector<double> getInverseResponse() const;
  //! The vignette as written to vignette.png, values in (0, 1] (all ones when the vignette is off).
  void getVignette(vpImage<float> &V) const;

  //! Render frame i (8-bit grey) with the configured effects.
  void render(unsigned int i, vpImage<unsigned char> &I) const;

  /*!
    Render the room seen from any camera pose, for example that of a camera moved by a simulator or a servo loop.
    Same intrinsics and photometric path as render(): vignette, response and noise when configured, at the base
    exposure (10 ms), without motion blur (one pose, no motion).
    \param wMc : camera-to-world pose, in the world frame of getPose() (metres).
    \param I : the 8-bit grey image, resized to getWidth() x getHeight().
    \param noiseSeed : selects the noise draw (with the configure() seed); give each image its own.
    \exception vpHSlamException::invalidArgument before configure().
  */
  void renderAtPose(const vpHomogeneousMatrix &wMc, vpImage<unsigned char> &I, unsigned int noiseSeed = 0) const;

  /*!
    The 3D world point (metres) seen at pixel (u, v) of frame i (at the frame's pose; with motion blur, the
    centre of the exposure).
  */
  vpColVector worldPointAt(double u, double v, unsigned int i) const;
  //! Depth (metres, along the optical axis) of the surface seen at pixel (u, v) of frame i.
  double depthAt(double u, double v, unsigned int i) const;

  /*!
    Render every frame and write the sequence into \e dir (created if needed); see the class documentation for
    the files.
    \exception vpHSlamException::invalidArgument naming the path when a folder or file cannot be written.
  */
  void writeSequence(const std::string &dir) const;

  /*!
    Hang a picture flat on one of the room's four walls, for example an AprilTag (the tag image with its white
    margin): its pixels replace the wall's texture inside a rectangle, the geometry stays the wall's, so depths and
    worldPointAt() are unchanged. It is drawn from the next render on, in every later configuration, until
    clearWallPictures().
    \param picture : grey image, printed as is (nearest texel up close, mip-mapped far away).
    \param centre : world point (metres) on a wall: x = -2.5 or 2.5, or z = -2 or 3.5 (the back and front walls).
    \param width : printed width in metres; the height follows the image's aspect ratio.
    \return wMp, the picture's frame: origin at its centre, x along its columns, y along its rows (down), z into the
    wall; the picture reads as printed from inside the room. For an AprilTag, the tag frame of
    vpDetectorAprilTag::getPose() (y up, z out of the tag) is this frame turned half a turn about x.
    \exception vpHSlamException::invalidArgument when the image is empty, the width not positive, the centre not on a
    wall, or the picture does not fit on it.
  */
  vpHomogeneousMatrix addWallPicture(const vpImage<unsigned char> &picture, const vpColVector &centre, double width);
  /*!
    Hang an AprilTag: addWallPicture() of \e tagImage (the tag as printed, one pixel per cell with its white margin)
    scaled so that its black square, \e blackCells cells wide, is \e tagSize metres (vpDetectorAprilTag's size).
    \return wMt, the tag's frame as vpDetectorAprilTag::getPose() gives it (origin at its centre, x right and y up as
    printed, z out of the wall): the picture's frame turned half a turn about x.
    \exception vpHSlamException::invalidArgument as addWallPicture(), and for blackCells 0 or over the image width.
  */
  vpHomogeneousMatrix addWallTag(const vpImage<unsigned char> &tagImage, unsigned int blackCells,
                                 const vpColVector &centre, double tagSize);
  //! Take every picture added by addWallPicture() down.
  void clearWallPictures();

  //! Photographs used as textures (for reports).
  std::vector<std::string> getTextureFiles() const;

private:
  void requireConfigured(const char *what) const;
  void requireFrame(unsigned int i, const char *what) const;
  void renderIrradiance(unsigned int i, std::vector<float> &E) const;
  //! Irradiance E to 8-bit grey: exposure ratio to the base exposure, vignette, response, noise seeded by \e seeds.
  void formImage(const std::vector<float> &E, double exposureRatio, const std::vector<unsigned int> &seeds,
                 vpImage<unsigned char> &I) const;
  //! Surface point Pw (world, metres) and its depth seen at pixel (u, v) of frame i; throws naming \e what if none.
  void surfaceAt(double u, double v, unsigned int i, const char *what, double Pw[3], double &depth) const;

  std::string m_imagesDataPath, m_loadedPath;
  unsigned int m_width, m_height, m_frames, m_seed;
  unsigned int m_laps = 1;
  bool m_lookOutward = false;
  double m_fps;
  Effects m_effects;
  std::unique_ptr<hslam::SyntheticRenderer> m_renderer;
  std::unique_ptr<hslam::SyntheticTrajectory> m_trajectory;
  std::vector<hslam::SimPicture> m_pictures; //!< hung on the walls; given to every renderer
  std::vector<float> m_vignette;             //!< per pixel, quantised to 8 bits as written (empty when off)
  std::vector<double> m_inverseResponse;
};

#endif
