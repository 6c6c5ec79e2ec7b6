// Checkpoints (constant-memory series) and the outflow meter built on it (issue 13: the
// meters of `run` grew with every frame, about 2.5 GB at the frame limit).
#include <metariver/checkpoints.h>
#include <metariver/emitters.h>

#include <gtest/gtest.h>

#include <cstdint>

namespace mr {
namespace {

TEST(Checkpoints, EveryRecordWhileWithinCapacity) {
    Checkpoints c(16, 2);
    for (int f = 0; f < 10; ++f) {
        const double r[2] = {double(f), double(10 * f)};
        c.push(r);
    }
    ASSERT_EQ(c.size(), 10u);
    EXPECT_EQ(c.stride(), 1u);
    for (size_t k = 0; k < 10; ++k) {
        EXPECT_EQ(c[k][0], double(k));
        EXPECT_EQ(c[k][1], double(10 * k));
    }
    EXPECT_EQ(c.column(1).back(), 90.0);
}

TEST(Checkpoints, BeyondCapacityEvenlySpacedWithTheLatestAndBounded) {
    Checkpoints c(8, 1);
    for (int f = 0; f < 1'000'003; ++f) {
        const double r[1] = {double(f)};
        c.push(r);
        ASSERT_LE(c.size(), c.capacity() + 1) << "frame " << f;
    }
    const std::vector<double> v = c.column(0);
    ASSERT_GE(v.size(), 5u);
    EXPECT_EQ(v.front(), 0.0);
    EXPECT_EQ(v.back(), 1'000'002.0) << "the latest frame is always kept";
    // Kept records are frames k * stride, the stride a power of two.
    const size_t s = c.stride();
    EXPECT_EQ(s & (s - 1), 0u);
    EXPECT_GE(double(s) * double(c.capacity()), 1'000'003.0 / 2.0);
    for (size_t k = 0; k + 1 < v.size(); ++k) EXPECT_EQ(v[k], double(k * s)) << k;
    EXPECT_EQ(c.fed(), 1'000'003u);
}

TEST(Checkpoints, TheLatestIsNotRepeatedWhenItIsAKeptFrame) {
    Checkpoints c(4, 1);
    for (int f = 0; f < 9; ++f) {  // capacity 4: strides 1, 2, 4; frame 8 is kept
        const double r[1] = {double(f)};
        c.push(r);
    }
    EXPECT_EQ(c.column(0), (std::vector<double>{0, 4, 8}));
}

TEST(FlowMeter, ARunLongerThanItsRecordsKeepsTheRatesAndTheFirstOutflow) {
    // A million frames: from 2.5 s on, 10 particles/s for the first half, then 30/s.
    FlowMeter m;
    const int frames = 1'000'000;
    const double dt = 1.0 / 60.0;
    double sunk = 0.0;
    for (int f = 1; f <= frames; ++f) {
        const double t = f * dt;
        if (t >= 2.5) sunk += (f <= frames / 2 ? 10.0 : 30.0) * dt;
        m.record(t, uint64_t(sunk));
    }
    const FlowMeter::Summary s = m.summary();
    EXPECT_NEAR(s.first_outflow_s, 2.6, dt);  // the first whole particle: 2.5 s + 1 / (10/s)
    // 1e6 frames in at most 4096 records: a stride of 256 frames, so the second half
    // starts within 256 frames (4 s of 8,333) of the exact frame, inside the 30/s part;
    // 0.03/s: the whole-particle truncation of the cumulative count.
    EXPECT_NEAR(s.rate, 30.0, 0.03);
    EXPECT_TRUE(s.steady);
    for (double w : s.windows) EXPECT_NEAR(w, 30.0, 0.1);  // quarters: 0.1/s, the same truncation
}

}  // namespace
}  // namespace mr
