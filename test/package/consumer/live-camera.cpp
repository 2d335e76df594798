#include <iostream>
#include <visp3/hslam/vpHSlam.h>
int main()
{
  vpHSlamImageSource::Options options;
  options.cameraFile = "camera.xml"; // your calibration (ViSP XML, DSO camera.txt, ...)
  std::unique_ptr<vpHSlamImageSource> camera = vpHSlamImageSource::create("/dev/video0", options);
  vpHSlam slam(*camera);
  vpImage<unsigned char> I;
  for (vpHSlamImageSource::Frame frame; camera->acquire(I, frame);)
    if (slam.track(I, frame.timestamp) == vpHSlam::stateTracking)
      std::cout << "wMc:\n" << slam.get_cMw().inverse() << std::endl;
}
