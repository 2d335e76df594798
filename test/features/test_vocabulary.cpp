// Vocabulary tree: hand-computed BoW vectors and scores, training (cluster recovery, determinism), file round trips
// between the binary, DBoW2 text and DBoW2 YAML formats, and every corrupt-file case.
#include "HSlamTestData.h"
#include "HSlamTestErrors.h"

#include "features/OrbVocabulary.h"
#include "features/VocabularyFiles.h"
#include "features/VocabularyTrainer.h"

#include <visp3/core/vpIoTools.h>
#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamVocabulary.h>

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <random>

#define HSLAM_EXPECT_ERROR(expr, code, text) hslam_test::expectHSlamError([&] { (void)(expr); }, code, {text})

namespace
{
using hslam::BowVector;
using hslam::OrbDescriptor;
using hslam::OrbVocabulary;

// root -> A (bits 0-99 clear), B (bits 0-99 set); A -> A1, A2; B -> B1, B2. Words: A1 0, A2 1, B1 2, B2 3.
OrbVocabulary::Parts handTree(hslam::VocabularyWeighting weighting)
{
  OrbVocabulary::Parts p;
  p.branching = 2;
  p.levels = 2;
  p.weighting = weighting;
  OrbDescriptor B;
  for (int b = 0; b < 100; ++b) {
    B.words[static_cast<std::size_t>(b >> 6)] |= std::uint64_t(1) << (b & 63);
  }
  const OrbDescriptor A;
  OrbDescriptor A2 = A, B2 = B;
  for (int b = 200; b < 230; ++b) {
    A2.words[static_cast<std::size_t>(b >> 6)] |= std::uint64_t(1) << (b & 63);
    B2.words[static_cast<std::size_t>(b >> 6)] |= std::uint64_t(1) << (b & 63);
  }
  p.parents = {0, 0, 0, 1, 1, 2, 2};
  p.descriptors = {OrbDescriptor(), A, B, A, A2, B, B2};
  p.wordNodes = {3, 4, 5, 6};
  p.wordWeights = {1.0, 2.0, 0.5, 0.0};
  return p;
}

OrbVocabulary handVocabulary(hslam::VocabularyWeighting weighting = hslam::VocabularyWeighting::tfIdf)
{
  OrbVocabulary v;
  v.assign(handTree(weighting), "hand tree");
  return v;
}

const OrbDescriptor &nodeDescriptor(const OrbVocabulary &v, std::uint32_t node)
{
  return v.descriptor(node);
}

TEST(Vocabulary, HandTreeWordsAndTfIdfVector)
{
  const OrbVocabulary v = handVocabulary();
  ASSERT_EQ(v.wordCount(), 4u);
  ASSERT_EQ(v.nodeCount(), 7u);
  const OrbDescriptor a1 = nodeDescriptor(v, 3), a2 = nodeDescriptor(v, 4), b1 = nodeDescriptor(v, 5);
  EXPECT_EQ(v.wordOf(a1), 0u);
  EXPECT_EQ(v.wordOf(a2), 1u);
  EXPECT_EQ(v.wordOf(b1), 2u);
  // A descriptor near A2 (a few bits off) still falls in A2.
  OrbDescriptor nearA2 = a2;
  nearA2.words[3] ^= 0x5ull;
  EXPECT_EQ(v.wordOf(nearA2), 1u);

  // Features: A1, A2, A2, B1, B2 (B2's weight is 0: skipped). TF-IDF sums: w0 1, w1 2 + 2, w2 0.5; total 5.5.
  BowVector bow;
  v.transform({a1, a2, a2, b1, nodeDescriptor(v, 6)}, bow);
  ASSERT_EQ(bow.size(), 3u);
  EXPECT_EQ(bow[0].wordId, 0u);
  EXPECT_NEAR(bow[0].weight, 1.0 / 5.5, 1e-15);
  EXPECT_EQ(bow[1].wordId, 1u);
  EXPECT_NEAR(bow[1].weight, 4.0 / 5.5, 1e-15);
  EXPECT_EQ(bow[2].wordId, 2u);
  EXPECT_NEAR(bow[2].weight, 0.5 / 5.5, 1e-15);
}

TEST(Vocabulary, WeightingSchemesAccumulateAsDbow2)
{
  // One feature in word 0 (weight 1), two in word 1 (weight 2).
  const OrbVocabulary tfidf = handVocabulary(hslam::VocabularyWeighting::tfIdf);
  const OrbDescriptor a2 = nodeDescriptor(tfidf, 4);
  const std::vector<OrbDescriptor> mix = {OrbDescriptor(), a2, a2};
  BowVector v;
  tfidf.transform(mix, v); // 1 and 2 + 2
  EXPECT_NEAR(v[0].weight, 1.0 / 5.0, 1e-15);
  handVocabulary(hslam::VocabularyWeighting::idf).transform(mix, v); // once per word: 1 and 2
  EXPECT_NEAR(v[0].weight, 1.0 / 3.0, 1e-15);
  handVocabulary(hslam::VocabularyWeighting::tf).transform(mix, v); // counts weighted by the stored weights
  EXPECT_NEAR(v[0].weight, 1.0 / 5.0, 1e-15);
  handVocabulary(hslam::VocabularyWeighting::binary).transform(mix, v);
  EXPECT_NEAR(v[0].weight, 1.0 / 3.0, 1e-15);
  handVocabulary().transform({}, v);
  EXPECT_TRUE(v.empty());
}

TEST(Vocabulary, L1ScoreOfHandComputedVectors)
{
  const BowVector a = {{0, 0.5}, {1, 0.5}};
  const BowVector b = {{1, 1.0}};
  const BowVector c = {{2, 0.25}, {7, 0.75}};
  // 1 - 0.5 (|0.5 - 0| + |0.5 - 1|) = 0.5
  EXPECT_NEAR(OrbVocabulary::score(a, b), 0.5, 1e-15);
  EXPECT_NEAR(OrbVocabulary::score(b, a), 0.5, 1e-15);
  EXPECT_NEAR(OrbVocabulary::score(a, a), 1.0, 1e-15);
  EXPECT_NEAR(OrbVocabulary::score(a, c), 0.0, 1e-15);
  const BowVector d = {{0, 0.2}, {1, 0.3}, {2, 0.5}};
  // 1 - 0.5 (0.3 + 0.2 + 0.5) = 0.5; equals sum of minima 0.2 + 0.3.
  EXPECT_NEAR(OrbVocabulary::score(a, d), 0.5, 1e-15);
  EXPECT_NEAR(OrbVocabulary::score({}, a), 0.0, 1e-15);
}

TEST(Vocabulary, DirectIndexGroupsFeaturesByNode)
{
  const OrbVocabulary v = handVocabulary();
  const OrbDescriptor a1 = nodeDescriptor(v, 3), a2 = nodeDescriptor(v, 4), b1 = nodeDescriptor(v, 5);
  BowVector bow;
  hslam::FeatureVector direct;
  v.transform({b1, a1, a2, b1}, bow, direct, 1); // depth L - 1 = 1: nodes A (1) and B (2)
  ASSERT_EQ(direct.size(), 2u);
  EXPECT_EQ(direct[0].nodeId, 1u);
  EXPECT_EQ(direct[0].features, (std::vector<std::uint32_t>{1, 2}));
  EXPECT_EQ(direct[1].nodeId, 2u);
  EXPECT_EQ(direct[1].features, (std::vector<std::uint32_t>{0, 3}));
  v.transform({b1, a1}, bow, direct, 0); // at the leaves
  ASSERT_EQ(direct.size(), 2u);
  EXPECT_EQ(direct[0].nodeId, 3u);
  EXPECT_EQ(direct[1].nodeId, 5u);
}

TEST(Vocabulary, BatchDescentGivesTheWordsOfOneAtATime)
{
  // transform() descends all descriptors together through the popcnt path where the processor has the instruction
  // (features/BinaryDescriptor.h); wordOf() takes one descriptor at a time through the portable count. On the
  // shipped vocabulary, with random descriptors and descriptors one bit from a centroid (ties between children are
  // likely there), both must give the same words and the same direct-index nodes.
  const std::string path = std::string(HSLAM_SOURCE_DIR) + "/data/hslam-orb.hvoc";
  std::ifstream probe(path);
  if (!probe) {
    GTEST_SKIP() << "no default vocabulary (data/hslam-orb.hvoc)";
  }
  const OrbVocabulary v = hslam::loadVocabulary(path);
  std::mt19937_64 rng(42);
  std::vector<OrbDescriptor> descriptors;
  for (int i = 0; i < 1500; ++i) {
    OrbDescriptor d;
    for (std::uint64_t &w : d.words) {
      w = rng();
    }
    if (i % 2 == 1) { // one bit away from the centroid of one of the first nodes (depths 1 and 2)
      d = v.descriptor(1u + static_cast<std::uint32_t>(i % 100));
      d.words[static_cast<std::size_t>(i % 4)] ^= std::uint64_t(1) << (i % 64);
    }
    descriptors.push_back(d);
  }
  constexpr int kLevelsUp = 2;
  BowVector bow;
  hslam::FeatureVector direct;
  v.transform(descriptors, bow, direct, kLevelsUp);
  std::vector<std::uint32_t> nodeOf(descriptors.size(), OrbVocabulary::kNoWord);
  for (const auto &entry : direct) {
    for (std::uint32_t f : entry.features) {
      nodeOf[f] = entry.nodeId;
    }
  }
  BowVector one;
  for (std::size_t i = 0; i < descriptors.size(); ++i) {
    std::uint32_t node = 0;
    const std::uint32_t word = v.wordOf(descriptors[i], v.levels() - kLevelsUp, &node);
    v.transform({descriptors[i]}, one);
    if (one.empty()) {
      continue; // a word of weight 0 is left out of both
    }
    ASSERT_EQ(one.size(), 1u);
    EXPECT_EQ(one[0].wordId, word) << "descriptor " << i;
    EXPECT_EQ(nodeOf[i], node) << "descriptor " << i;
  }
  EXPECT_GT(bow.size(), 500u); // many words reached (825 here)
}

TEST(Vocabulary, AssignRejectsWhatIsNotATree)
{
  OrbVocabulary v;
  auto parts = handTree(hslam::VocabularyWeighting::tfIdf);
  parts.parents[3] = 5; // a parent after its child
  HSLAM_EXPECT_ERROR(v.assign(parts, "bad.voc"), vpHSlamException::parseError, "bad.voc");
  parts = handTree(hslam::VocabularyWeighting::tfIdf);
  parts.wordNodes[0] = 1; // an inner node as a word
  HSLAM_EXPECT_ERROR(v.assign(parts, "bad.voc"), vpHSlamException::parseError, "node 1");
  parts = handTree(hslam::VocabularyWeighting::tfIdf);
  parts.wordWeights[1] = std::nan("");
  HSLAM_EXPECT_ERROR(v.assign(parts, "bad.voc"), vpHSlamException::parseError, "weight");
  parts = handTree(hslam::VocabularyWeighting::tfIdf);
  parts.levels = 1; // leaves at depth 2
  HSLAM_EXPECT_ERROR(v.assign(parts, "bad.voc"), vpHSlamException::parseError, "deeper");
  EXPECT_TRUE(v.empty());
}

// Ten random centres, 60 noisy copies each (up to 12 of 256 bits flipped); the copies of centre c are spread over
// the four images 4c .. 4c + 3 of 40.
std::vector<std::vector<OrbDescriptor>> clusteredImages(std::uint32_t seed,
                                                        std::vector<std::pair<OrbDescriptor, int>> *labelled = nullptr)
{
  std::mt19937_64 rng(seed);
  std::vector<OrbDescriptor> centres(10);
  for (OrbDescriptor &c : centres) {
    for (auto &w : c.words) {
      w = rng();
    }
  }
  std::vector<std::vector<OrbDescriptor>> images(40);
  for (int c = 0; c < 10; ++c) {
    for (int i = 0; i < 60; ++i) {
      OrbDescriptor d = centres[static_cast<std::size_t>(c)];
      for (int f = 0; f < 12; ++f) {
        const int bit = static_cast<int>(rng() % 256);
        d.words[static_cast<std::size_t>(bit >> 6)] ^= std::uint64_t(1) << (bit & 63);
      }
      images[static_cast<std::size_t>(4 * c + i % 4)].push_back(d);
      if (labelled) {
        labelled->emplace_back(d, c);
      }
    }
  }
  return images;
}

TEST(VocabularyTraining, RecoversSeparatedClustersWithIdfWeights)
{
  std::vector<std::pair<OrbDescriptor, int>> labelled;
  const auto images = clusteredImages(3, &labelled);
  hslam::VocabularyTrainingOptions options;
  options.branching = 10;
  options.levels = 1;
  const OrbVocabulary v = hslam::trainVocabulary(images, options);
  ASSERT_EQ(v.wordCount(), 10u);
  // Every copy of a centre falls into that centre's word, and the ten centres into ten different words.
  std::vector<std::uint32_t> wordOfLabel(10, OrbVocabulary::kNoWord);
  for (const auto &dl : labelled) {
    const std::uint32_t word = v.wordOf(dl.first);
    std::uint32_t &expected = wordOfLabel[static_cast<std::size_t>(dl.second)];
    if (expected == OrbVocabulary::kNoWord) {
      expected = word;
    }
    EXPECT_EQ(word, expected);
  }
  std::sort(wordOfLabel.begin(), wordOfLabel.end());
  EXPECT_EQ(std::unique(wordOfLabel.begin(), wordOfLabel.end()), wordOfLabel.end());
  // Each word is seen in 4 of the 40 images: IDF log(40 / 4).
  for (std::size_t w = 0; w < v.wordCount(); ++w) {
    EXPECT_NEAR(v.wordWeight(static_cast<std::uint32_t>(w)), std::log(10.0), 1e-12);
  }
}

TEST(VocabularyTraining, DeterministicForASeedAndDifferentAcrossSeeds)
{
  const auto images = clusteredImages(5);
  hslam::VocabularyTrainingOptions options;
  options.branching = 4;
  options.levels = 4;
  const OrbVocabulary a = hslam::trainVocabulary(images, options);
  const OrbVocabulary b = hslam::trainVocabulary(images, options);
  EXPECT_EQ(a.fingerprint(), b.fingerprint());
  const std::string dir = vpIoTools::makeTempDirectory("/tmp/hslam-voc-XXXXXX");
  hslam::saveVocabulary(a, dir + "/a.hvoc", hslam::VocabularyFormat::binary);
  hslam::saveVocabulary(b, dir + "/b.hvoc", hslam::VocabularyFormat::binary);
  std::ifstream fa(dir + "/a.hvoc", std::ios::binary), fb(dir + "/b.hvoc", std::ios::binary);
  const std::string bytesA((std::istreambuf_iterator<char>(fa)), std::istreambuf_iterator<char>());
  const std::string bytesB((std::istreambuf_iterator<char>(fb)), std::istreambuf_iterator<char>());
  EXPECT_FALSE(bytesA.empty());
  EXPECT_EQ(bytesA, bytesB);
  options.seed = 2;
  EXPECT_NE(hslam::trainVocabulary(images, options).fingerprint(), a.fingerprint());
  vpIoTools::remove(dir);
}

TEST(VocabularyTraining, RejectsTooFewDescriptorsAndBadOptions)
{
  hslam::VocabularyTrainingOptions options;
  HSLAM_EXPECT_ERROR(hslam::trainVocabulary({{OrbDescriptor()}}, options), vpHSlamException::invalidArgument,
                     "descriptors");
  options.branching = 1;
  HSLAM_EXPECT_ERROR(hslam::trainVocabulary(clusteredImages(1), options), vpHSlamException::invalidArgument, "k =");
}

class VocabularyFiles : public ::testing::Test
{
protected:
  void SetUp() override
  {
    m_dir = vpIoTools::makeTempDirectory("/tmp/hslam-vocfiles-XXXXXX");
    hslam::VocabularyTrainingOptions options;
    options.branching = 5;
    options.levels = 3;
    m_vocabulary = hslam::trainVocabulary(clusteredImages(7), options);
    std::mt19937_64 rng(11);
    for (int i = 0; i < 300; ++i) {
      OrbDescriptor d;
      for (auto &w : d.words) {
        w = rng();
      }
      m_probe.push_back(d);
    }
    for (const auto &image : clusteredImages(8)) {
      m_probe.insert(m_probe.end(), image.begin(), image.end());
    }
  }
  void TearDown() override { vpIoTools::remove(m_dir); }

  std::string path(const std::string &name) const { return m_dir + "/" + name; }
  std::string readBytes(const std::string &file) const
  {
    std::ifstream in(file, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }
  void writeBytes(const std::string &file, const std::string &bytes) const
  {
    std::ofstream out(file, std::ios::binary);
    out << bytes;
  }
  void expectSameVectors(const OrbVocabulary &a, const OrbVocabulary &b) const
  {
    BowVector va, vb;
    hslam::FeatureVector fa, fb;
    a.transform(m_probe, va, fa, 1);
    b.transform(m_probe, vb, fb, 1);
    ASSERT_FALSE(va.empty());
    EXPECT_EQ(va, vb);
    EXPECT_EQ(fa, fb);
  }

  std::string m_dir;
  OrbVocabulary m_vocabulary;
  std::vector<OrbDescriptor> m_probe;
};

TEST_F(VocabularyFiles, BinaryTextYamlRoundTripGivesIdenticalVectors)
{
  hslam::saveVocabulary(m_vocabulary, path("v.hvoc"), hslam::VocabularyFormat::binary);
  const OrbVocabulary fromBinary = hslam::loadVocabulary(path("v.hvoc"));
  hslam::saveVocabulary(fromBinary, path("v.txt"), hslam::VocabularyFormat::dbow2Text);
  EXPECT_EQ(hslam::detectVocabularyFormat(path("v.txt")), hslam::VocabularyFormat::dbow2Text);
  const OrbVocabulary fromText = hslam::loadVocabulary(path("v.txt"));
  hslam::saveVocabulary(fromText, path("v.yml.gz"), hslam::VocabularyFormat::dbow2Yaml);
  EXPECT_EQ(hslam::detectVocabularyFormat(path("v.yml.gz")), hslam::VocabularyFormat::dbow2Yaml);
  const OrbVocabulary fromYaml = hslam::loadVocabulary(path("v.yml.gz"));
  hslam::saveVocabulary(fromYaml, path("v.yml"), hslam::VocabularyFormat::dbow2Yaml);
  const OrbVocabulary fromPlainYaml = hslam::loadVocabulary(path("v.yml"));
  hslam::saveVocabulary(fromPlainYaml, path("back.hvoc"), hslam::VocabularyFormat::binary);

  for (const OrbVocabulary *v : {&fromBinary, &fromText, &fromYaml, &fromPlainYaml}) {
    expectSameVectors(m_vocabulary, *v);
    EXPECT_EQ(v->fingerprint(), m_vocabulary.fingerprint());
  }
  EXPECT_EQ(readBytes(path("v.hvoc")), readBytes(path("back.hvoc")));
  EXPECT_FALSE(vpIoTools::checkFilename(path("v.hvoc.partial")));
}

TEST_F(VocabularyFiles, ReadsTheDbow2YamlFixtureAndConvertsIt)
{
  HSLAM_REQUIRE_SHARED_DATA(fixture, "vocab_format/dbow2_small_k9_L3.yml.gz");
  const OrbVocabulary v = hslam::loadVocabulary(fixture);
  EXPECT_EQ(v.branching(), 9);
  EXPECT_EQ(v.levels(), 3);
  EXPECT_EQ(v.weighting(), hslam::VocabularyWeighting::tfIdf);
  EXPECT_EQ(v.wordCount(), 692u); // word ids 0..691 in the file
  EXPECT_GT(v.nodeCount(), v.wordCount());
  hslam::saveVocabulary(v, path("fixture.hvoc"), hslam::VocabularyFormat::binary);
  hslam::saveVocabulary(v, path("fixture.yml.gz"), hslam::VocabularyFormat::dbow2Yaml);
  expectSameVectors(v, hslam::loadVocabulary(path("fixture.hvoc")));
  expectSameVectors(v, hslam::loadVocabulary(path("fixture.yml.gz")));
}

TEST_F(VocabularyFiles, CorruptBinaryFilesNameTheFileAndTheProblem)
{
  hslam::saveVocabulary(m_vocabulary, path("good.hvoc"), hslam::VocabularyFormat::binary);
  const std::string good = readBytes(path("good.hvoc"));

  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(path("missing.hvoc")), vpHSlamException::fileNotFound, "missing.hvoc");
  writeBytes(path("empty.hvoc"), "");
  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(path("empty.hvoc")), vpHSlamException::parseError, "empty");

  std::string bytes = good;
  bytes[0] = 'X';
  writeBytes(path("magic.hvoc"), bytes);
  HSLAM_EXPECT_ERROR(hslam::loadVocabularyBinary(path("magic.hvoc")), vpHSlamException::parseError, "wrong magic");
  // Detected as text then: still a clear error naming the file.
  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(path("magic.hvoc")), vpHSlamException::parseError, "magic.hvoc");

  writeBytes(path("truncated.hvoc"), good.substr(0, good.size() - 20));
  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(path("truncated.hvoc")), vpHSlamException::parseError, "truncated");
  writeBytes(path("header.hvoc"), good.substr(0, 20));
  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(path("header.hvoc")), vpHSlamException::parseError, "truncated");
  writeBytes(path("trailing.hvoc"), good + "xx");
  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(path("trailing.hvoc")), vpHSlamException::parseError, "unexpected bytes");

  bytes = good;
  bytes[good.size() / 2] = static_cast<char>(bytes[good.size() / 2] ^ 0x10);
  writeBytes(path("flipped.hvoc"), bytes);
  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(path("flipped.hvoc")), vpHSlamException::parseError, "checksum");

  bytes = good;
  bytes[12] = 64; // 512-bit descriptors
  writeBytes(path("size.hvoc"), bytes);
  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(path("size.hvoc")), vpHSlamException::unsupported, "64 bytes");

  bytes = good;
  bytes[8] = 2; // a newer version
  writeBytes(path("version.hvoc"), bytes);
  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(path("version.hvoc")), vpHSlamException::unsupported, "version 2");

  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(m_dir), vpHSlamException::fileUnreadable, "folder");
  HSLAM_EXPECT_ERROR(hslam::saveVocabulary(OrbVocabulary(), path("e.hvoc"), hslam::VocabularyFormat::binary),
                     vpHSlamException::invalidArgument, "empty");
}

TEST_F(VocabularyFiles, CorruptTextAndYamlFilesNameTheFileAndTheProblem)
{
  hslam::saveVocabulary(m_vocabulary, path("good.txt"), hslam::VocabularyFormat::dbow2Text);
  const std::string good = readBytes(path("good.txt"));

  writeBytes(path("cut.txt"), good.substr(0, good.size() / 2)); // cut inside a line
  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(path("cut.txt")), vpHSlamException::parseError, "cut.txt:");
  const std::size_t firstLineEnd = good.find('\n');
  writeBytes(path("headeronly.txt"), good.substr(0, firstLineEnd + 1));
  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(path("headeronly.txt")), vpHSlamException::parseError, "empty");
  writeBytes(path("badheader.txt"), "10 6\n");
  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(path("badheader.txt")), vpHSlamException::parseError, "badheader.txt:1");
  writeBytes(path("scoring.txt"), "10 6 9 0\n");
  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(path("scoring.txt")), vpHSlamException::parseError, "scoring");
  std::string wide = "2 1 0 0\n0 1";
  for (int j = 0; j < 64; ++j) {
    wide += " 7";
  }
  wide += " 0.5\n";
  writeBytes(path("wide.txt"), wide);
  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(path("wide.txt")), vpHSlamException::unsupported, "64 bytes");
  writeBytes(path("garbage.txt"), "this is not a vocabulary\n");
  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(path("garbage.txt")), vpHSlamException::parseError, "garbage.txt:1");

  writeBytes(path("novoc.yml"), "%YAML:1.0\n---\nsomething: 3\n");
  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(path("novoc.yml")), vpHSlamException::parseError, "vocabulary");
  writeBytes(path("broken.yml"), "%YAML:1.0\n---\nvocabulary: { k: 2, L: [\n");
  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(path("broken.yml")), vpHSlamException::parseError, "broken.yml");
  writeBytes(path("short.yml"), "%YAML:1.0\n---\nvocabulary:\n  k: 2\n  L: 1\n  scoringType: 0\n  weightingType: 0\n"
                                "  nodes:\n    - { nodeId: 1, parentId: 0, weight: 1., descriptor: \"1 2 3 \" }\n"
                                "  words:\n    - { wordId: 0, nodeId: 1 }\n");
  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(path("short.yml")), vpHSlamException::unsupported, "3 bytes");
  writeBytes(path("empty.yml"), "%YAML:1.0\n---\nvocabulary:\n  k: 2\n  L: 1\n  scoringType: 0\n  weightingType: 0\n"
                                "  nodes: []\n  words: []\n");
  HSLAM_EXPECT_ERROR(hslam::loadVocabulary(path("empty.yml")), vpHSlamException::parseError, "empty");
}

TEST(VocabularyPublic, LoadsSavesAndDescribes)
{
  const std::string dir = vpIoTools::makeTempDirectory("/tmp/hslam-vocpub-XXXXXX");
  hslam::VocabularyTrainingOptions options;
  options.branching = 4;
  options.levels = 3;
  const vpHSlamVocabulary v(hslam::trainVocabulary(clusteredImages(2), options));
  v.save(dir + "/v.hvoc");
  const vpHSlamVocabulary loaded = vpHSlamVocabulary::load(dir + "/v.hvoc");
  EXPECT_EQ(loaded.getFingerprint(), v.getFingerprint());
  EXPECT_EQ(loaded.getBranching(), 4u);
  EXPECT_NE(loaded.describe().find("k = 4"), std::string::npos);
  EXPECT_EQ(vpHSlamVocabulary::parseFormat("text"), vpHSlamVocabulary::formatDbow2Text);
  HSLAM_EXPECT_ERROR(vpHSlamVocabulary::parseFormat("xml"), vpHSlamException::invalidArgument, "xml");
  EXPECT_TRUE(vpHSlamVocabulary().empty());
  vpIoTools::remove(dir);
}
} // namespace
