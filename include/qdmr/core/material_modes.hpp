#pragma once
// The modes a material picks (technique, lighting, shadow, ambient occlusion, blending) and the specular-from-albedo
// rule: the vocabulary the scene description (qdmr/scene/scene.hpp) and the shading programs (src/program/,
// src/kernel/) share. In core, so that the programs reach none of the scene's headers.
namespace qdmr {

// Specular reflectance generated from the albedo instead of stored (the talk's terrain saves the texture):
// specular = scale * pow(invert ? 1 - luminance : luminance, power), luminance = Rec. 709 weights of the linear
// albedo, clamped to [0, 1].
struct SpecularFromAlbedo {
  bool enabled = false;  // off: the material's lighting.specular constant
  float power = 1.0f;
  float scale = 0.5f;
  bool invert = false;
};

enum class TechniqueKind { Normal, Relief, Pom, Csm, Rcsm, Qdm };
// QDM: where to continue after the ray crosses into a neighbouring cell.
enum class QdmLevelUp { Stay, One, Aligned };
// QDM: how the level-0 hit is refined between texels.
enum class QdmRefinement { None, Linear, Binary, BilinearPatch };
// How techniques fetch heights: the nearest or the bilinear level-0 texel (the box and bilinear surfaces the
// exact reference knows), or trilinear with the pixel's LOD. QDM walks its max-quadtree with point fetches
// unless trilinear (the talk: LinearMipMapLinear "possible but may introduce some artifacts").
enum class HeightFetch { Point, Bilinear, Trilinear };

enum class LightingModel { BlinnPhong, CookTorrance };

// Self-shadowing of the displaced surface towards each directional light (the talk's "Self-shadowing").
enum class ShadowMode { Off, Hard, Horizon, QdmSoft };
// How the horizon shadow combines the occlusion of its samples along the light direction.
enum class ProfileOperator { Max, Min, Average };

// Ambient occlusion of the displaced surface from horizon queries (applied to the ambient light).
enum class AoMode { Off, Frame, Baked };

// Height blending of up to 4 layers (the talk's "Surface Blending" / "Height Blending").
enum class BlendOperator { Alpha, Height, HeightWidth };
// Where blend weights come from: the vertices (interpolated, constant along each view ray), or a per-pixel
// weight texture sampled where the ray hits.
enum class WeightMode { Vertex, Pixel };

}  // namespace qdmr
