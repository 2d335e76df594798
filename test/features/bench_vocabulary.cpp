// Place-recognition costs on one core: loading the shipped vocabulary (binary) and the same vocabulary written as
// DBoW2 text, and the BoW transform of one keyframe's descriptors (1000 and 2000, from a real image).
#include "HSlamTestData.h"

#include "features/OrbExtractor.h"
#include "features/VocabularyFiles.h"

#include <visp3/core/vpIoTools.h>
#include <visp3/hslam/vpHSlamVocabulary.h>
#include <visp3/io/vpImageIo.h>

#include <benchmark/benchmark.h>

#include <filesystem>
#include <iostream>

namespace
{
const std::string &shippedPath()
{
  static const std::string path = vpHSlamVocabulary::defaultPath();
  return path;
}

//! The shipped vocabulary written once as DBoW2 text in a temporary folder.
const std::string &textCopyPath()
{
  static std::string path;
  if (path.empty() && !shippedPath().empty()) {
    const std::string dir = vpIoTools::makeTempDirectory("/tmp/hslam-bench-voc-XXXXXX");
    path = dir + "/vocabulary.txt";
    hslam::saveVocabulary(hslam::loadVocabulary(shippedPath()), path, hslam::VocabularyFormat::dbow2Text);
    std::cout << "shipped vocabulary: " << shippedPath() << " " << std::filesystem::file_size(shippedPath())
              << " bytes; as DBoW2 text: " << std::filesystem::file_size(path) << " bytes" << std::endl;
  }
  return path;
}

void BM_LoadShippedBinary(benchmark::State &state)
{
  if (shippedPath().empty()) {
    state.SkipWithError("no shipped vocabulary");
    return;
  }
  for (auto _ : state) {
    hslam::OrbVocabulary v = hslam::loadVocabulary(shippedPath());
    benchmark::DoNotOptimize(v.wordCount());
  }
}
BENCHMARK(BM_LoadShippedBinary)->Unit(benchmark::kMillisecond)->Iterations(5);

void BM_LoadSameAsDbow2Text(benchmark::State &state)
{
  if (textCopyPath().empty()) {
    state.SkipWithError("no shipped vocabulary");
    return;
  }
  for (auto _ : state) {
    hslam::OrbVocabulary v = hslam::loadVocabulary(textCopyPath());
    benchmark::DoNotOptimize(v.wordCount());
  }
}
BENCHMARK(BM_LoadSameAsDbow2Text)->Unit(benchmark::kMillisecond)->Iterations(2);

//! A full k = 10, L = 6 tree (10^6 words, random centroids) written once in the binary format.
const std::string &millionWordPath()
{
  static std::string path;
  if (path.empty()) {
    hslam::OrbVocabulary::Parts parts;
    parts.branching = 10;
    parts.levels = 6;
    parts.parents.assign(1, 0);
    std::uint64_t state = 1;
    auto next = [&state] {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      return state;
    };
    std::vector<std::uint32_t> level = {0};
    for (int depth = 0; depth < parts.levels; ++depth) {
      std::vector<std::uint32_t> children;
      for (std::uint32_t parent : level) {
        for (int c = 0; c < parts.branching; ++c) {
          children.push_back(static_cast<std::uint32_t>(parts.parents.size()));
          parts.parents.push_back(parent);
        }
      }
      level.swap(children);
    }
    parts.descriptors.resize(parts.parents.size());
    for (hslam::OrbDescriptor &d : parts.descriptors) {
      for (auto &w : d.words) {
        w = next();
      }
    }
    for (std::uint32_t leaf : level) {
      parts.wordNodes.push_back(leaf);
      parts.wordWeights.push_back(1.0 + static_cast<double>(next() % 1000) / 100.0);
    }
    hslam::OrbVocabulary v;
    v.assign(std::move(parts), "random tree");
    path = vpIoTools::makeTempDirectory("/tmp/hslam-bench-voc-XXXXXX") + "/million.hvoc";
    hslam::saveVocabulary(v, path, hslam::VocabularyFormat::binary);
    std::cout << "10^6-word binary vocabulary: " << std::filesystem::file_size(path) << " bytes" << std::endl;
  }
  return path;
}

void BM_LoadMillionWordBinary(benchmark::State &state)
{
  for (auto _ : state) {
    hslam::OrbVocabulary v = hslam::loadVocabulary(millionWordPath());
    benchmark::DoNotOptimize(v.wordCount());
  }
}
BENCHMARK(BM_LoadMillionWordBinary)->Unit(benchmark::kMillisecond)->Iterations(3);

void BM_TransformKeyframe(benchmark::State &state)
{
  const std::string image = hslam_test::sharedData("7scenes_redkitchen_000-299/rgb/000100.jpg");
  if (shippedPath().empty() || image.empty()) {
    state.SkipWithError("no shipped vocabulary or no 7-Scenes image");
    return;
  }
  static const hslam::OrbVocabulary vocabulary = hslam::loadVocabulary(shippedPath());
  vpImage<unsigned char> I;
  vpImageIo::read(I, image);
  hslam::OrbExtractorOptions options;
  options.maxFeatures = static_cast<int>(state.range(0));
  options.fastThreshold = 5;
  hslam::OrbExtractor extractor(options);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  extractor.extract(I, keypoints, descriptors);
  const std::vector<hslam::OrbDescriptor> features = hslam::descriptorsFromMat(descriptors);
  hslam::BowVector bow;
  hslam::FeatureVector direct;
  for (auto _ : state) {
    vocabulary.transform(features, bow, direct, 4);
    benchmark::DoNotOptimize(bow.data());
  }
  state.counters["descriptors"] = static_cast<double>(features.size());
}
BENCHMARK(BM_TransformKeyframe)->Arg(1000)->Arg(2000)->Unit(benchmark::kMillisecond);
} // namespace
