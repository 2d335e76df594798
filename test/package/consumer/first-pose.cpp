//! \example first-pose.cpp
//! From an installed H-SLAM to a first pose: open a dataset folder, track its frames, print the camera poses.
//!
//!   ./first-pose /data/kitti/sequences/06 [max frames]
#include <visp3/hslam/vpHSlam.h>
#include <visp3/hslam/vpHSlamImageSource.h>

#include <cstdlib>
#include <iostream>

int main(int argc, char **argv)
{
  if (argc < 2) {
    std::cerr << "usage: " << argv[0] << " DATASET_FOLDER [MAX_FRAMES]\n";
    return EXIT_FAILURE;
  }
  try {
    vpHSlamImageSource::Options options;
    options.maxFrames = argc > 2 ? static_cast<unsigned int>(std::atoi(argv[2])) : 0;
    std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(argv[1], options);
    vpHSlamParameters parameters;
    parameters.system.deterministic = true; // same output on every run
    vpHSlam slam(*source, parameters);

    vpImage<unsigned char> I;
    vpHSlamImageSource::Frame frame;
    unsigned int tracked = 0;
    while (source->acquire(I, frame)) {
      if (slam.track(I, frame.timestamp, frame.exposure) == vpHSlam::stateTracking) {
        ++tracked;
        std::cout << "frame " << frame.index << " wMc t = " << slam.get_cMw().inverse().getTranslationVector().t()
                  << std::endl;
      }
    }
    std::cout << "tracked " << tracked << " frames" << std::endl;
    return tracked > 0 ? EXIT_SUCCESS : EXIT_FAILURE;
  } catch (const vpException &e) {
    std::cerr << "error: " << e.getStringMessage() << std::endl;
    return EXIT_FAILURE;
  }
}
