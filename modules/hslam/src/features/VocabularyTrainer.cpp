/*
 * H-SLAM for ViSP.
 */
#include "features/VocabularyTrainer.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

namespace hslam
{
namespace
{
//! splitmix64: a counter-based generator whose output is the same on every platform.
class SplitMix64
{
public:
  explicit SplitMix64(std::uint64_t seed) : m_state(seed) {}
  std::uint64_t next()
  {
    std::uint64_t z = (m_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  //! Uniform in [0, n), n > 0 (multiply-high: no modulo bias worth mentioning, and portable).
  std::uint64_t below(std::uint64_t n)
  {
    return static_cast<std::uint64_t>((static_cast<unsigned __int128>(next()) * n) >> 64);
  }

private:
  std::uint64_t m_state;
};

//! Bit majority of a group (DBoW2 FORB::meanValue: a bit is set when at least half the group, rounded up, has it).
OrbDescriptor bitMajority(const std::vector<OrbDescriptor> &all, const std::vector<std::uint32_t> &group)
{
  std::array<std::uint32_t, 256> counts{};
  for (std::uint32_t index : group) {
    const OrbDescriptor &d = all[index];
    for (int w = 0; w < 4; ++w) {
      const std::uint64_t x = d.words[w];
      std::uint32_t *c = counts.data() + 64 * w;
      for (int b = 0; b < 64; ++b) {
        c[b] += static_cast<std::uint32_t>((x >> b) & 1u);
      }
    }
  }
  OrbDescriptor mean;
  const std::uint64_t n = group.size();
  for (int b = 0; b < 256; ++b) {
    if (2 * static_cast<std::uint64_t>(counts[b]) >= n) {
      mean.words[b >> 6] |= std::uint64_t(1) << (b & 63);
    }
  }
  return mean;
}

class HierarchicalKmeans
{
public:
  HierarchicalKmeans(const std::vector<OrbDescriptor> &all, const VocabularyTrainingOptions &options,
                     const std::function<void(double)> &progress)
      : m_all(all), m_options(options), m_progress(progress)
  {
  }

  //! Builds parents and descriptors of every node (node 0 = root).
  void run(OrbVocabulary::Parts &parts)
  {
    m_parents = &parts.parents;
    m_descriptors = &parts.descriptors;
    m_parents->assign(1, 0);
    m_descriptors->assign(1, OrbDescriptor());
    std::vector<std::uint32_t> members(m_all.size());
    for (std::size_t i = 0; i < members.size(); ++i) {
      members[i] = static_cast<std::uint32_t>(i);
    }
    split(0, members, 0);
  }

private:
  void finished(std::size_t count)
  {
    m_done += count;
    if (m_progress && !m_all.empty()) {
      const int percent = static_cast<int>((100 * m_done) / m_all.size());
      if (percent != m_lastPercent) {
        m_lastPercent = percent;
        m_progress(static_cast<double>(m_done) / static_cast<double>(m_all.size()));
      }
    }
  }

  //! k-means++ seeding then Lloyd iterations; groups left empty are dropped.
  void kmeans(std::uint32_t node, const std::vector<std::uint32_t> &members, std::vector<OrbDescriptor> &centres,
              std::vector<std::vector<std::uint32_t>> &groups)
  {
    const std::size_t k = static_cast<std::size_t>(m_options.branching);
    SplitMix64 rng(m_options.seed * 0x2545f4914f6cdd1dull + node);
    centres.clear();
    centres.push_back(m_all[members[rng.below(members.size())]]);
    // Squared distance to the nearest centre so far (k-means++ samples proportionally to it).
    std::vector<std::uint64_t> nearest2(members.size());
    for (std::size_t i = 0; i < members.size(); ++i) {
      const std::uint64_t d = static_cast<std::uint64_t>(hammingDistance(m_all[members[i]], centres[0]));
      nearest2[i] = d * d;
    }
    while (centres.size() < k) {
      std::uint64_t total = 0;
      for (std::uint64_t d2 : nearest2) {
        total += d2;
      }
      if (total == 0) {
        break; // every descriptor equals a centre already
      }
      std::uint64_t r = rng.below(total);
      std::size_t chosen = 0;
      while (r >= nearest2[chosen]) {
        r -= nearest2[chosen];
        ++chosen;
      }
      centres.push_back(m_all[members[chosen]]);
      for (std::size_t i = 0; i < members.size(); ++i) {
        const std::uint64_t d = static_cast<std::uint64_t>(hammingDistance(m_all[members[i]], centres.back()));
        nearest2[i] = std::min(nearest2[i], d * d);
      }
    }

    std::vector<std::uint32_t> assignment(members.size(), 0xffffffffu);
    for (int iteration = 0; iteration < m_options.maxKmeansIterations; ++iteration) {
      bool changed = false;
      for (std::size_t i = 0; i < members.size(); ++i) {
        const OrbDescriptor &d = m_all[members[i]];
        std::uint32_t best = 0;
        int bestDistance = hammingDistance(d, centres[0]);
        for (std::size_t c = 1; c < centres.size(); ++c) {
          const int distance = hammingDistance(d, centres[c]);
          if (distance < bestDistance) {
            bestDistance = distance;
            best = static_cast<std::uint32_t>(c);
          }
        }
        if (assignment[i] != best) {
          assignment[i] = best;
          changed = true;
        }
      }
      groups.assign(centres.size(), {});
      for (std::size_t i = 0; i < members.size(); ++i) {
        groups[assignment[i]].push_back(members[i]);
      }
      if (!changed && iteration > 0) {
        break;
      }
      for (std::size_t c = 0; c < centres.size(); ++c) {
        if (!groups[c].empty()) {
          centres[c] = bitMajority(m_all, groups[c]);
        }
      }
    }
    std::size_t kept = 0;
    for (std::size_t c = 0; c < centres.size(); ++c) {
      if (!groups[c].empty()) {
        centres[kept] = centres[c];
        groups[kept].swap(groups[c]);
        ++kept;
      }
    }
    centres.resize(kept);
    groups.resize(kept);
  }

  void split(std::uint32_t node, std::vector<std::uint32_t> &members, int depth)
  {
    if (depth >= m_options.levels || members.size() <= 1) {
      finished(members.size());
      return; // a leaf
    }
    std::vector<OrbDescriptor> centres;
    std::vector<std::vector<std::uint32_t>> groups;
    if (members.size() <= static_cast<std::size_t>(m_options.branching)) {
      // DBoW2: as many clusters as descriptors, each its own centroid.
      for (std::uint32_t index : members) {
        centres.push_back(m_all[index]);
        groups.push_back({index});
      }
    } else {
      kmeans(node, members, centres, groups);
    }
    if (groups.size() < 2) {
      finished(members.size());
      return; // identical descriptors: nothing to split
    }
    std::vector<std::uint32_t>().swap(members); // the groups hold them now
    const std::uint32_t firstChild = static_cast<std::uint32_t>(m_parents->size());
    for (const OrbDescriptor &centre : centres) {
      m_parents->push_back(node);
      m_descriptors->push_back(centre);
    }
    for (std::size_t c = 0; c < groups.size(); ++c) {
      split(firstChild + static_cast<std::uint32_t>(c), groups[c], depth + 1);
    }
  }

  const std::vector<OrbDescriptor> &m_all;
  const VocabularyTrainingOptions &m_options;
  const std::function<void(double)> &m_progress;
  std::vector<std::uint32_t> *m_parents = nullptr;
  std::vector<OrbDescriptor> *m_descriptors = nullptr;
  std::size_t m_done = 0;
  int m_lastPercent = -1;
};
} // namespace

OrbVocabulary trainVocabulary(const std::vector<std::vector<OrbDescriptor>> &images,
                              const VocabularyTrainingOptions &options, const std::function<void(double)> &progress)
{
  if (options.branching < 2 || options.branching > OrbVocabulary::kMaxBranching || options.levels < 1 ||
      options.levels > OrbVocabulary::kMaxLevels || options.maxKmeansIterations < 1) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "vocabulary training: need 2 <= k <= " + std::to_string(OrbVocabulary::kMaxBranching) +
                               ", 1 <= L <= " + std::to_string(OrbVocabulary::kMaxLevels) +
                               " and at least one k-means iteration (got k = " + std::to_string(options.branching) +
                               ", L = " + std::to_string(options.levels) + ")");
  }
  std::vector<OrbDescriptor> all;
  for (const auto &image : images) {
    all.insert(all.end(), image.begin(), image.end());
  }
  if (all.size() < static_cast<std::size_t>(options.branching) || all.size() >= OrbVocabulary::kNoWord) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "vocabulary training: " + std::to_string(all.size()) +
                               " descriptors in the training images, need at least k = " +
                               std::to_string(options.branching) + " (are the images blank or too small?)");
  }

  OrbVocabulary::Parts parts;
  parts.branching = options.branching;
  parts.levels = options.levels;
  parts.weighting = options.weighting;
  parts.scoring = VocabularyScoring::l1;
  HierarchicalKmeans(all, options, progress).run(parts);
  std::vector<OrbDescriptor>().swap(all);

  // Words: the leaves, numbered in node order (as DBoW2's createWords).
  std::vector<bool> hasChildren(parts.parents.size(), false);
  for (std::size_t n = 1; n < parts.parents.size(); ++n) {
    hasChildren[parts.parents[n]] = true;
  }
  for (std::size_t n = 1; n < parts.parents.size(); ++n) {
    if (!hasChildren[n]) {
      parts.wordNodes.push_back(static_cast<std::uint32_t>(n));
    }
  }
  parts.wordWeights.assign(parts.wordNodes.size(), 1.0);
  OrbVocabulary vocabulary;
  vocabulary.assign(parts, "trained vocabulary");

  if (options.weighting == VocabularyWeighting::tfIdf || options.weighting == VocabularyWeighting::idf) {
    // IDF: images whose descriptors reach each word through the tree (DBoW2 setNodeWeights).
    std::vector<std::uint32_t> imagesWithWord(parts.wordNodes.size(), 0);
    std::vector<std::uint32_t> lastImage(parts.wordNodes.size(), 0xffffffffu);
    for (std::size_t i = 0; i < images.size(); ++i) {
      for (const OrbDescriptor &d : images[i]) {
        const std::uint32_t word = vocabulary.wordOf(d);
        if (lastImage[word] != i) {
          lastImage[word] = static_cast<std::uint32_t>(i);
          ++imagesWithWord[word];
        }
      }
    }
    const double imageCount = static_cast<double>(images.size());
    for (std::size_t w = 0; w < parts.wordWeights.size(); ++w) {
      parts.wordWeights[w] = imagesWithWord[w] > 0 ? std::log(imageCount / imagesWithWord[w]) : 0.0;
    }
    vocabulary.assign(std::move(parts), "trained vocabulary");
  }
  if (progress) {
    progress(1.0);
  }
  return vocabulary;
}
} // namespace hslam
