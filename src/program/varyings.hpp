#pragma once
// Per-vertex values the rasterizer interpolates for the programs, in this order. Programs say how many they
// read: the blend weights are interpolated only for programs that blend layers per vertex.
namespace qdmr {

enum Varying : int { kWorldX, kWorldY, kWorldZ, kNormalX, kNormalY, kNormalZ, kTangentX, kTangentY, kTangentZ, kTangentW, kU, kV,
                     kWeight0, kWeight1, kWeight2, kWeight3, kVaryingCount };
inline constexpr int kBaseVaryingCount = kWeight0;  // everything but the blend weights

}  // namespace qdmr
