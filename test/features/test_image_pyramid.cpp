// ImagePyramid: level counts (DSO rule, odd sizes), exact gradients and means on known images, intrinsics per
// level consistent with the 2x2-mean pixel convention, bilinear interpolation, buffer reuse, the noise estimate.
#include "HSlamTestData.h"

#include "features/ImagePyramid.h"

#include <visp3/hslam/vpHSlamException.h>

#include <cmath>
#include <random>

namespace
{
constexpr int kMaxLevels = 6;
constexpr int kMinCoarsestPixels = 5000; // DSO

hslam::PinholeIntrinsics vgaIntrinsics()
{
  return {525., 524., 319.5, 239.5};
}

// I(x, y) = a x + b y + c, exactly representable in float for these small integer coefficients.
vpImage<float> ramp(int w, int h, float a, float b, float c)
{
  vpImage<float> I(static_cast<unsigned int>(h), static_cast<unsigned int>(w));
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      I[y][x] = a * static_cast<float>(x) + b * static_cast<float>(y) + c;
    }
  }
  return I;
}
} // namespace

TEST(ImagePyramid, LevelSizesFollowDsoRuleWithFloorDivision)
{
  struct Case {
    int w, h, levels, coarsestW, coarsestH;
  };
  // DSO: add a level while the current coarsest has > 5000 pixels. Odd sizes: floor division.
  const Case cases[] = {{640, 480, 4, 80, 60}, {752, 480, 5, 47, 30}, {1226, 370, 5, 76, 23}};
  for (const Case &c : cases) {
    hslam::ImagePyramid pyr;
    pyr.build(ramp(c.w, c.h, 1.f, 1.f, 0.f), vgaIntrinsics(), kMaxLevels, kMinCoarsestPixels);
    ASSERT_EQ(pyr.numLevels(), c.levels) << c.w << "x" << c.h;
    EXPECT_EQ(hslam::ImagePyramid::levelCount(c.w, c.h, kMaxLevels, kMinCoarsestPixels), c.levels);
    int w = c.w, h = c.h;
    for (int l = 0; l < pyr.numLevels(); ++l) {
      EXPECT_EQ(pyr.level(l).width, w) << "level " << l;
      EXPECT_EQ(pyr.level(l).height, h) << "level " << l;
      EXPECT_EQ(pyr.level(l).color.size(), static_cast<size_t>(w * h));
      EXPECT_EQ(pyr.level(l).gradSq.size(), static_cast<size_t>(w * h));
      w /= 2;
      h /= 2;
    }
    EXPECT_EQ(pyr.level(c.levels - 1).width, c.coarsestW);
    EXPECT_EQ(pyr.level(c.levels - 1).height, c.coarsestH);
  }
  // maxLevels bounds the count.
  EXPECT_EQ(hslam::ImagePyramid::levelCount(640, 480, 2, kMinCoarsestPixels), 2);
  EXPECT_EQ(hslam::ImagePyramid::levelCount(640, 480, 1, kMinCoarsestPixels), 1);
}

TEST(ImagePyramid, RampGradientsAndMeansAreExact)
{
  const float a = 2.f, b = 3.f, c = 10.f;
  const int w = 1226, h = 370; // odd level sizes appear at level 1 (613x185)
  hslam::ImagePyramid pyr;
  pyr.build(ramp(w, h, a, b, c), vgaIntrinsics(), kMaxLevels, kMinCoarsestPixels);
  ASSERT_EQ(pyr.numLevels(), 5);
  for (int l = 0; l < pyr.numLevels(); ++l) {
    const hslam::PyramidLevel &L = pyr.level(l);
    // Level l pixel x covers level-0 pixels 2^l x .. 2^l x + 2^l - 1: mean position 2^l x + (2^l - 1) / 2.
    const float s = static_cast<float>(1 << l);
    const float off = (s - 1.f) * 0.5f;
    int bad = 0;
    for (int y = 0; y < L.height; ++y) {
      for (int x = 0; x < L.width; ++x) {
        const Eigen::Vector3f &p = L.color[static_cast<size_t>(y * L.width + x)];
        const float expectI = a * (s * x + off) + b * (s * y + off) + c;
        const float dx = a * s, dy = b * s; // per level-l pixel, borders included (one-sided differences)
        if (p[0] != expectI || p[1] != dx || p[2] != dy ||
            L.gradSq[static_cast<size_t>(y * L.width + x)] != dx * dx + dy * dy) {
          ++bad;
        }
      }
    }
    EXPECT_EQ(bad, 0) << "level " << l;
  }
}

TEST(ImagePyramid, IntrinsicsConsistentAcrossLevels)
{
  const hslam::PinholeIntrinsics K0 = vgaIntrinsics();
  hslam::ImagePyramid pyr;
  pyr.build(ramp(640, 480, 1.f, 0.f, 0.f), K0, kMaxLevels, kMinCoarsestPixels);
  const double X[3][3] = {{0.3, -0.2, 2.0}, {-1.1, 0.7, 3.5}, {0.01, 0.02, 0.8}};
  for (int l = 0; l < pyr.numLevels(); ++l) {
    const hslam::PinholeIntrinsics &K = pyr.level(l).K;
    const double scale = std::ldexp(1.0, l);
    EXPECT_DOUBLE_EQ(K.fx, K0.fx / scale);
    EXPECT_DOUBLE_EQ(K.fy, K0.fy / scale);
    for (const auto &P : X) {
      const double u0 = K0.fx * P[0] / P[2] + K0.cx, v0 = K0.fy * P[1] / P[2] + K0.cy;
      const double ul = K.fx * P[0] / P[2] + K.cx, vl = K.fy * P[1] / P[2] + K.cy;
      EXPECT_NEAR(ul, (u0 + 0.5) / scale - 0.5, 1e-12) << "level " << l;
      EXPECT_NEAR(vl, (v0 + 0.5) / scale - 0.5, 1e-12) << "level " << l;
    }
  }
}

TEST(ImagePyramid, InterpolateIsExactOnBilinearImage)
{
  // I = x y + 2 x + 3 y + 1 is bilinear: bilinear interpolation reproduces it exactly at any (u, v).
  const int w = 64, h = 48;
  vpImage<float> I(h, w);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      I[y][x] = static_cast<float>(x * y + 2 * x + 3 * y + 1);
    }
  }
  hslam::ImagePyramid pyr;
  pyr.build(I, vgaIntrinsics(), 1, kMinCoarsestPixels);
  const hslam::PyramidLevel &L = pyr.level(0);
  const float samples[][2] = {{1.25f, 1.5f}, {10.75f, 20.125f}, {30.5f, 40.0625f}, {61.875f, 45.5f}};
  for (const auto &s : samples) {
    const float u = s[0], v = s[1];
    ASSERT_TRUE(L.isInside(u, v, 0.f));
    const double expected = static_cast<double>(u) * v + 2. * u + 3. * v + 1.;
    EXPECT_NEAR(L.interpolateIntensity(u, v), expected, 1e-3);
    EXPECT_NEAR(L.interpolate(u, v)[0], expected, 1e-3);
    // Inside, the central-difference gradient of x y + 2 x + 3 y is exact at pixels: (y + 2, x + 3), bilinear too.
    if (u >= 1.f && v >= 1.f && u < w - 2.f && v < h - 2.f) {
      EXPECT_NEAR(L.interpolate(u, v)[1], v + 2., 1e-3);
      EXPECT_NEAR(L.interpolate(u, v)[2], u + 3., 1e-3);
    }
  }
}

TEST(ImagePyramid, EightBitOverloadMatchesFloatAndBuffersAreReused)
{
  vpImage<unsigned char> I8(480, 640);
  vpImage<float> If(480, 640);
  for (unsigned int i = 0; i < I8.getSize(); ++i) {
    I8.bitmap[i] = static_cast<unsigned char>((i * 7919u) % 251u);
    If.bitmap[i] = static_cast<float>(I8.bitmap[i]);
  }
  hslam::ImagePyramid p8, pf;
  p8.build(I8, vgaIntrinsics(), kMaxLevels, kMinCoarsestPixels);
  pf.build(If, vgaIntrinsics(), kMaxLevels, kMinCoarsestPixels);
  ASSERT_EQ(p8.numLevels(), pf.numLevels());
  for (int l = 0; l < p8.numLevels(); ++l) {
    EXPECT_TRUE(p8.level(l).color == pf.level(l).color) << "level " << l;
  }
  const Eigen::Vector3f *before = pf.level(0).color.data();
  const float *beforeCoarse = pf.level(3).gradSq.data();
  pf.build(If, vgaIntrinsics(), kMaxLevels, kMinCoarsestPixels);
  EXPECT_EQ(pf.level(0).color.data(), before);
  EXPECT_EQ(pf.level(3).gradSq.data(), beforeCoarse);
}

// The definition, pass by pass and pixel by pixel: copy, 2x2 means, central differences (one-sided at the borders).
std::vector<std::vector<float>> referenceLevels(const vpImage<float> &I, int levels)
{
  std::vector<std::vector<float>> out; // per level: I, dx, dy, gradSq per pixel
  int w = static_cast<int>(I.getWidth()), h = static_cast<int>(I.getHeight());
  std::vector<float> intensity(I.bitmap, I.bitmap + I.getSize());
  for (int l = 0; l < levels; ++l) {
    std::vector<float> level;
    const auto at = [&](int x, int y) { return intensity[static_cast<size_t>(y * w + x)]; };
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const float dx = x == 0       ? at(1, y) - at(0, y)
                         : x == w - 1 ? at(w - 1, y) - at(w - 2, y)
                                      : 0.5f * (at(x + 1, y) - at(x - 1, y));
        const float dy = y == 0       ? at(x, 1) - at(x, 0)
                         : y == h - 1 ? at(x, h - 1) - at(x, h - 2)
                                      : 0.5f * (at(x, y + 1) - at(x, y - 1));
        level.insert(level.end(), {at(x, y), dx, dy, dx * dx + dy * dy});
      }
    }
    out.push_back(level);
    std::vector<float> coarse;
    for (int y = 0; y < h / 2; ++y) {
      for (int x = 0; x < w / 2; ++x) {
        coarse.push_back(0.25f *
                         (at(2 * x, 2 * y) + at(2 * x + 1, 2 * y) + at(2 * x, 2 * y + 1) + at(2 * x + 1, 2 * y + 1)));
      }
    }
    intensity.swap(coarse);
    w /= 2;
    h /= 2;
  }
  return out;
}

TEST(ImagePyramid, EqualsThePixelByPixelDefinitionOnRandomImagesOfAnySize)
{
  // Widths that are not multiples of the vector width and odd sizes at every level, down to 2 pixels.
  const int sizes[][2] = {{2, 2}, {3, 2}, {2, 3}, {5, 7}, {13, 11}, {37, 29}, {101, 83}, {1226, 370}};
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> value(0.f, 255.f);
  for (const auto &size : sizes) {
    vpImage<float> I(static_cast<unsigned int>(size[1]), static_cast<unsigned int>(size[0]));
    for (unsigned int i = 0; i < I.getSize(); ++i) {
      I.bitmap[i] = value(rng);
    }
    hslam::ImagePyramid pyr;
    pyr.build(I, vgaIntrinsics(), kMaxLevels, 20);
    const std::vector<std::vector<float>> ref = referenceLevels(I, pyr.numLevels());
    for (int l = 0; l < pyr.numLevels(); ++l) {
      const hslam::PyramidLevel &L = pyr.level(l);
      int bad = 0;
      for (size_t i = 0; i < L.color.size(); ++i) {
        const float *r = &ref[static_cast<size_t>(l)][4 * i];
        bad += (L.color[i][0] != r[0] || L.color[i][1] != r[1] || L.color[i][2] != r[2] || L.gradSq[i] != r[3]);
      }
      EXPECT_EQ(bad, 0) << size[0] << "x" << size[1] << " level " << l;
    }
  }
}

TEST(ImagePyramid, RejectsBadInput)
{
  hslam::ImagePyramid pyr;
  EXPECT_THROW(pyr.build(vpImage<float>(), vgaIntrinsics(), kMaxLevels, kMinCoarsestPixels), vpHSlamException);
  EXPECT_THROW(pyr.build(ramp(16, 16, 1.f, 1.f, 0.f), vgaIntrinsics(), 0, kMinCoarsestPixels), vpHSlamException);
}

TEST(ImagePyramid, NoiseEstimateRecoversGaussianNoiseAndIgnoresSmoothStructure)
{
  // A ramp has no Laplacian: zero noise; Gaussian noise of known sigma added to a smooth shading is recovered
  // (Immerkaer's estimator is unbiased for white Gaussian noise; 300k pixels make its spread ~0.3 %).
  const int w = 640, h = 480;
  hslam::ImagePyramid pyr;
  pyr.build(ramp(w, h, 0.2f, 0.1f, 50.f), vgaIntrinsics(), kMaxLevels, kMinCoarsestPixels);
  EXPECT_NEAR(hslam::estimateNoiseSigma(pyr.level(0)), 0., 1e-3);
  std::mt19937 rng(42);
  std::normal_distribution<double> noise(0., 1.);
  for (double sigma : {1., 4.}) {
    vpImage<float> I(static_cast<unsigned int>(h), static_cast<unsigned int>(w));
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const double shading = 100. + 40. * std::sin(x / 90.) * std::cos(y / 70.);
        I[y][x] = static_cast<float>(shading + sigma * noise(rng));
      }
    }
    pyr.build(I, vgaIntrinsics(), kMaxLevels, kMinCoarsestPixels);
    EXPECT_NEAR(hslam::estimateNoiseSigma(pyr.level(0)), sigma, 0.03 * sigma) << "sigma " << sigma;
  }
  hslam::PyramidLevel tiny;
  tiny.width = tiny.height = 2;
  tiny.color.assign(4, Eigen::Vector3f::Zero());
  EXPECT_EQ(hslam::estimateNoiseSigma(tiny), 0.);
}
