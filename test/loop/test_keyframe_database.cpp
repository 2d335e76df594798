// Keyframe database: inverted index bookkeeping, scoring, exclusion, expected-score normalisation, co-visibility
// grouping, and concurrent use.
#include "HSlamTestErrors.h"
#include "HSlamTestHeap.h"

#include "features/OrbVocabulary.h"
#include "loop/KeyframeDatabase.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <map>
#include <random>
#include <thread>

namespace
{
using hslam::BowVector;
using hslam::KeyframeDatabase;

// Vectors over 10 words with known pairwise L1 scores (sum of minima).
const BowVector kQuery = {{0, 0.25}, {1, 0.25}, {2, 0.25}, {3, 0.25}};
const BowVector kA = {{0, 0.25}, {1, 0.25}, {2, 0.25}, {5, 0.25}}; // 0.75 with the query
const BowVector kB = {{0, 0.25}, {1, 0.25}, {2, 0.25}, {6, 0.25}}; // 0.75
const BowVector kC = {{0, 0.25}, {1, 0.25}, {2, 0.20}, {4, 0.30}}; // 0.70
const BowVector kD = {{7, 0.5}, {8, 0.5}};                         // 0

TEST(KeyframeDatabase, AddRemoveAndErrors)
{
  KeyframeDatabase db(10);
  db.add(1, kA);
  db.add(2, kB);
  EXPECT_EQ(db.size(), 2u);
  EXPECT_TRUE(db.contains(1));
  hslam_test::expectHSlamError([&] { db.add(1, kC); }, vpHSlamException::invalidArgument, {"already"});
  hslam_test::expectHSlamError(
      [&] {
        db.add(9, {{12, 1.0}});
      },
      vpHSlamException::invalidArgument, {"outside the vocabulary"});
  EXPECT_FALSE(db.contains(9));
  EXPECT_TRUE(db.remove(1));
  EXPECT_FALSE(db.remove(1));
  EXPECT_FALSE(db.contains(1));
  const auto result = db.query(kQuery, KeyframeDatabase::Query());
  ASSERT_EQ(result.size(), 1u);
  EXPECT_EQ(result[0].id, 2);
  db.clear();
  EXPECT_EQ(db.size(), 0u);
  EXPECT_TRUE(db.query(kQuery, KeyframeDatabase::Query()).empty());
}

TEST(KeyframeDatabase, ScoresFiltersAndNormalises)
{
  KeyframeDatabase db(10);
  db.add(1, kA);
  db.add(3, kC);
  db.add(4, kD);
  KeyframeDatabase::Query q;
  auto result = db.query(kQuery, q);
  ASSERT_EQ(result.size(), 2u); // D shares no word
  EXPECT_EQ(result[0].id, 1);
  EXPECT_NEAR(result[0].score, 0.75, 1e-12);
  EXPECT_EQ(result[0].commonWords, 3);
  EXPECT_EQ(result[1].id, 3);
  EXPECT_NEAR(result[1].score, 0.70, 1e-12);
  EXPECT_EQ(result[1].commonWords, 3);

  q.excluded = [](int id) { return id == 3; };
  result = db.query(kQuery, q);
  ASSERT_EQ(result.size(), 1u);
  EXPECT_EQ(result[0].id, 1);

  q.excluded = nullptr;
  q.minScore = 0.72;
  result = db.query(kQuery, q);
  ASSERT_EQ(result.size(), 1u);
  EXPECT_EQ(result[0].id, 1);

  // Expected score 0.8 (the query with its best co-visible neighbour): 0.75 / 0.8 and 0.70 / 0.8.
  q.minScore = 0.0;
  q.expectedScore = 0.8;
  q.minNormalizedScore = 0.9;
  result = db.query(kQuery, q);
  ASSERT_EQ(result.size(), 1u);
  EXPECT_NEAR(result[0].normalizedScore, 0.9375, 1e-12);
  EXPECT_EQ(db.scoresWith(kQuery, {3, 42, 1}), (std::vector<double>{0.70, 0.75}));
}

TEST(KeyframeDatabase, MinCommonWordsRatioSkipsWeakOverlaps)
{
  KeyframeDatabase db(10);
  db.add(1, kC);                   // 3 common words
  db.add(2, {{0, 0.5}, {9, 0.5}}); // 1 common word: below 0.8 * 3
  const auto result = db.query(kQuery, KeyframeDatabase::Query());
  ASSERT_EQ(result.size(), 1u);
  EXPECT_EQ(result[0].id, 1);
}

TEST(KeyframeDatabase, CovisibilityGroupsAccumulateAndKeepTheBestMember)
{
  // B (0.75) and C (0.70) see each other; A (0.75) is alone. Groups: {B, C} 1.45 and {A} 0.75 < 0.75 * 1.45.
  KeyframeDatabase db(10);
  db.add(1, kA);
  db.add(2, kB);
  db.add(3, kC);
  KeyframeDatabase::Query q;
  q.covisible = [](int id) {
    if (id == 2) {
      return std::vector<int>{3};
    }
    if (id == 3) {
      return std::vector<int>{2};
    }
    return std::vector<int>{};
  };
  auto result = db.query(kQuery, q);
  ASSERT_EQ(result.size(), 1u);
  EXPECT_EQ(result[0].id, 2);
  EXPECT_NEAR(result[0].groupScore, 1.45, 1e-12);
  EXPECT_NEAR(result[0].score, 0.75, 1e-12);

  // Without grouping every candidate stands alone, best first, ties by id.
  q.covisible = nullptr;
  result = db.query(kQuery, q);
  ASSERT_EQ(result.size(), 3u);
  EXPECT_EQ(result[0].id, 1);
  EXPECT_EQ(result[1].id, 2);
  EXPECT_EQ(result[2].id, 3);
  q.maxCandidates = 2;
  EXPECT_EQ(db.query(kQuery, q).size(), 2u);
}

TEST(KeyframeDatabase, ConcurrentAddsRemovesAndQueries)
{
  KeyframeDatabase db(10);
  std::atomic<bool> stop(false);
  std::atomic<int> answered(0);
  std::thread reader([&] {
    while (!stop) {
      for (const auto &c : db.query(kQuery, KeyframeDatabase::Query())) {
        EXPECT_GE(c.score, 0.0);
        EXPECT_LE(c.score, 1.0 + 1e-12);
      }
      ++answered;
    }
  });
  while (answered.load() == 0) {
    std::this_thread::yield(); // the reader is running before the writes start
  }
  const int before = answered.load();
  for (int i = 0; i < 2000; ++i) {
    db.add(i, (i % 3 == 0) ? kA : (i % 3 == 1 ? kC : kD));
    if (i % 2 == 0) {
      db.remove(i);
    }
  }
  while (answered.load() < before + 2) {
    std::this_thread::yield(); // and answers again while the database is full
  }
  stop = true;
  reader.join();
  EXPECT_EQ(db.size(), 1000u);
}
// Words held by many keyframes (a room revisited lap after lap) leave their chain for a list of their own; keyframes
// leaving must leave the index as if they had never come: after removing two thirds and adding others, every query
// answers as a database built from the keyframes present.
TEST(KeyframeDatabase, ManyHoldersPerWordAnswerAsAFreshDatabaseAfterRemovals)
{
  std::mt19937 rng(5);
  auto randomVector = [&rng]() {
    std::vector<std::uint32_t> words;
    for (int i = 0; i < 60; ++i) {
      words.push_back(static_cast<std::uint32_t>(rng() % 200)); // 200 words: each held by tens of keyframes
    }
    std::sort(words.begin(), words.end());
    words.erase(std::unique(words.begin(), words.end()), words.end());
    BowVector bow;
    for (std::uint32_t w : words) {
      bow.push_back({w, 1. / static_cast<double>(words.size())});
    }
    return bow;
  };
  std::map<int, BowVector> present;
  KeyframeDatabase db(200);
  for (int k = 0; k < 150; ++k) {
    present[k] = randomVector();
    db.add(k, present[k]);
  }
  for (int k = 0; k < 150; ++k) {
    if (k % 3 != 0) {
      ASSERT_TRUE(db.remove(k));
      present.erase(k);
    }
  }
  for (int k = 150; k < 200; ++k) {
    present[k] = randomVector();
    db.add(k, present[k]);
  }
  KeyframeDatabase fresh(200);
  for (const auto &kv : present) {
    fresh.add(kv.first, kv.second);
  }
  ASSERT_EQ(db.size(), fresh.size());
  KeyframeDatabase::Query q;
  q.excluded = [](int id) { return id % 7 == 0; };
  for (int i = 0; i < 20; ++i) {
    const BowVector query = randomVector();
    const auto a = db.query(query, q), b = fresh.query(query, q);
    ASSERT_EQ(a.size(), b.size());
    ASSERT_FALSE(a.empty());
    for (std::size_t c = 0; c < a.size(); ++c) {
      EXPECT_EQ(a[c].id, b[c].id);
      EXPECT_EQ(a[c].commonWords, b[c].commonWords);
      EXPECT_DOUBLE_EQ(a[c].score, b[c].score);
    }
  }
  // Everything removed: nothing found, and the index holds no list any more.
  const double emptyBytes = KeyframeDatabase(200).memoryBytes();
  for (const auto &kv : present) {
    ASSERT_TRUE(db.remove(kv.first));
  }
  EXPECT_TRUE(db.query(randomVector(), q).empty());
  EXPECT_EQ(db.size(), 0u);
  EXPECT_GT(db.memoryBytes(), emptyBytes - 1.); // pools keep their capacity until clear()
  db.clear();
  EXPECT_LE(db.memoryBytes(), emptyBytes + 64.);
}

TEST(KeyframeDatabase, MemoryCountIsTheHeapItTakes)
{
  // memoryBytes() goes into the statistics' memory per stored keyframe: it must be what the inverted index and the
  // stored vectors take from the heap, hash nodes and growth slack included.
  if (!hslam_test::heapMeasurable()) {
    GTEST_SKIP() << "needs glibc's own malloc (mallinfo2) to measure the heap";
  }
  constexpr std::uint32_t kWords = 100000;
  std::mt19937 rng(3);
  std::vector<BowVector> vectors;
  for (int k = 0; k < 60; ++k) {
    std::vector<std::uint32_t> words;
    for (int i = 0; i < 400; ++i) {
      words.push_back(static_cast<std::uint32_t>(rng() % 3000)); // shared words: index lists of many keyframes
    }
    std::sort(words.begin(), words.end());
    words.erase(std::unique(words.begin(), words.end()), words.end());
    BowVector bow;
    for (std::uint32_t w : words) {
      bow.push_back({w, 1. / static_cast<double>(words.size())});
    }
    vectors.push_back(bow);
  }
  const double heapBefore = hslam_test::heapInUse();
  KeyframeDatabase db(kWords);
  for (int k = 0; k < 60; ++k) {
    db.add(k, vectors[static_cast<std::size_t>(k)]);
  }
  const double heap = hslam_test::heapInUse() - heapBefore;
  const double counted = db.memoryBytes();
  std::printf("60 keyframes: heap %.1f KB, counted %.1f KB\n", heap / 1024., counted / 1024.);
  EXPECT_NEAR(counted, heap, 0.05 * heap);
  // The count is kept up to date as keyframes leave (culling), not recomputed from the whole index.
  for (int k = 0; k < 60; k += 3) {
    ASSERT_TRUE(db.remove(k));
  }
  const double heapAfter = hslam_test::heapInUse() - heapBefore;
  std::printf("40 keyframes left: heap %.1f KB, counted %.1f KB\n", heapAfter / 1024., db.memoryBytes() / 1024.);
  EXPECT_LT(heapAfter, heap);
  EXPECT_NEAR(db.memoryBytes(), heapAfter, 0.05 * heapAfter);
}
} // namespace
