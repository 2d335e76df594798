// Retrieval quality of the vocabulary + keyframe database on sequences with ground truth (issue acceptance):
// every frame queries a database of the frames at least `minGap` frames away; a returned frame is correct when its
// ground-truth pose lies within a distance and an angle of the query's.
#ifndef HSLAM_TEST_PLACE_RECOGNITION_EVAL_H
#define HSLAM_TEST_PLACE_RECOGNITION_EVAL_H

#include "features/BinaryDescriptor.h"
#include "features/OrbExtractor.h"
#include "features/OrbVocabulary.h"
#include "loop/KeyframeDatabase.h"

#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpThetaUVector.h>
#include <visp3/hslam/vpHSlamImageSource.h>
#include <visp3/hslam/vpHSlamTrajectory.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

namespace hslam_test
{
//! Descriptors and ground-truth poses of every frame of a sequence.
struct DescribedSequence {
  std::vector<std::vector<hslam::OrbDescriptor>> descriptors;
  std::vector<vpHomogeneousMatrix> wMc;
};

//! Reads a TUM RGB-D or KITTI folder with its TUM ground truth file, ORB features per frame (1000, as the trainer).
inline DescribedSequence describeSequence(const std::string &folder, const std::string &groundTruthTum)
{
  DescribedSequence out;
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(folder);
  const vpHSlamTrajectory gt = vpHSlamTrajectory::readTum(groundTruthTum);
  hslam::OrbExtractor extractor;
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  while (source->acquire(I, frame)) {
    // Nearest ground-truth stamp (the shared sequences have one pose per frame).
    const std::vector<double> &stamps = gt.getTimestamps();
    const auto it = std::lower_bound(stamps.begin(), stamps.end(), frame.timestamp - 1e-6);
    if (it == stamps.end() || std::fabs(*it - frame.timestamp) > 0.01) {
      continue;
    }
    extractor.extract(I, keypoints, descriptors);
    out.descriptors.push_back(hslam::descriptorsFromMat(descriptors));
    out.wMc.push_back(gt.get_wMc(static_cast<std::size_t>(it - stamps.begin())));
  }
  return out;
}

struct RetrievalResult {
  int queries = 0;
  int queriesWithTruth = 0; //!< queries with at least one correct frame in their database
  int correctTop1 = 0;
  double precisionAt1 = 0.0; //!< correct rank-1 answers / queries with truth
  double recallAt95Precision =
      0.0; //!< best recall (over queries with truth) at a score threshold with precision >= 0.95
  double medianTransformMs = 0.0;
  double maxWrongConfidence = 0.0;    //!< highest normalised score of a wrong rank-1 answer
  double medianRightConfidence = 0.0; //!< median normalised score of the right rank-1 answers
};

inline bool samePlace(const vpHomogeneousMatrix &a, const vpHomogeneousMatrix &b, double maxDistance,
                      double maxAngleDeg)
{
  const vpHomogeneousMatrix aMb = a.inverse() * b;
  const double angle = vpThetaUVector(aMb.getRotationMatrix()).getTheta() * 180.0 / M_PI;
  return aMb.getTranslationVector().frobeniusNorm() <= maxDistance && angle <= maxAngleDeg;
}

/*!
  Every frame queries the database of all frames, excluding the ones closer than minGap in time. Frames within
  `neighbourhood` frames of a database frame are its co-visible neighbours (they share most of their points), and
  the expected score of a query is its score with its adjacent frame.
*/
inline RetrievalResult evaluateRetrieval(const hslam::OrbVocabulary &vocabulary, const DescribedSequence &sequence,
                                         double maxDistance, double maxAngleDeg, int minGap = 30, int neighbourhood = 3)
{
  const int n = static_cast<int>(sequence.descriptors.size());
  std::vector<hslam::BowVector> bows(static_cast<std::size_t>(n));
  std::vector<double> times;
  hslam::KeyframeDatabase database(vocabulary.wordCount());
  for (int i = 0; i < n; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    vocabulary.transform(sequence.descriptors[static_cast<std::size_t>(i)], bows[static_cast<std::size_t>(i)]);
    times.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    database.add(i, bows[static_cast<std::size_t>(i)]);
  }
  RetrievalResult result;
  std::sort(times.begin(), times.end());
  result.medianTransformMs = times.empty() ? 0.0 : times[times.size() / 2];

  struct Answer {
    double confidence;
    bool correct;
  };
  std::vector<Answer> answers;
  for (int q = 0; q < n; ++q) {
    const vpHomogeneousMatrix &wMq = sequence.wMc[static_cast<std::size_t>(q)];
    bool hasTruth = false;
    for (int j = 0; j < n && !hasTruth; ++j) {
      hasTruth = std::abs(j - q) >= minGap &&
                 samePlace(wMq, sequence.wMc[static_cast<std::size_t>(j)], maxDistance, maxAngleDeg);
    }
    ++result.queries;
    result.queriesWithTruth += hasTruth ? 1 : 0;

    hslam::KeyframeDatabase::Query query;
    query.excluded = [&](int id) { return std::abs(id - q) < minGap; };
    query.covisible = [&](int id) {
      std::vector<int> neighbours;
      for (int d = 1; d <= neighbourhood; ++d) {
        for (int j : {id - d, id + d}) {
          if (j >= 0 && j < n) {
            neighbours.push_back(j);
          }
        }
      }
      return neighbours;
    };
    const int adjacent = q + 1 < n ? q + 1 : q - 1;
    query.expectedScore = database.scoresWith(bows[static_cast<std::size_t>(q)], {adjacent}).front();
    const std::vector<hslam::KeyframeDatabase::Candidate> candidates =
        database.query(bows[static_cast<std::size_t>(q)], query);
    if (candidates.empty()) {
      continue;
    }
    const bool correct =
        samePlace(wMq, sequence.wMc[static_cast<std::size_t>(candidates.front().id)], maxDistance, maxAngleDeg);
    result.correctTop1 += (correct && hasTruth) ? 1 : 0;
    answers.push_back({candidates.front().normalizedScore, correct});
  }
  result.precisionAt1 = result.queriesWithTruth > 0 ? double(result.correctTop1) / result.queriesWithTruth : 0.0;
  std::sort(answers.begin(), answers.end(),
            [](const Answer &a, const Answer &b) { return a.confidence > b.confidence; });
  std::vector<double> right;
  for (const Answer &a : answers) {
    if (a.correct) {
      right.push_back(a.confidence);
    } else {
      result.maxWrongConfidence = std::max(result.maxWrongConfidence, a.confidence);
    }
  }
  result.medianRightConfidence = right.empty() ? 0.0 : right[right.size() / 2];
  int accepted = 0, correct = 0;
  for (std::size_t i = 0; i < answers.size(); ++i) {
    ++accepted;
    correct += answers[i].correct ? 1 : 0;
    const bool thresholdEndsHere = i + 1 == answers.size() || answers[i + 1].confidence < answers[i].confidence;
    if (thresholdEndsHere && correct >= 0.95 * accepted && result.queriesWithTruth > 0) {
      result.recallAt95Precision = std::max(result.recallAt95Precision, double(correct) / result.queriesWithTruth);
    }
  }
  return result;
}
} // namespace hslam_test

#endif
