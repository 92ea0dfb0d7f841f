#pragma once
// SceneDesc: what a scene file says, as plain validated values (no JSON past the loader).
// Units: lengths in scene units, angles in degrees, colours linear RGB.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "qdmr/core/sampling.hpp"
#include "qdmr/core/texture_cache.hpp"
#include "qdmr/core/material_modes.hpp"

namespace qdmr {

struct MeshData;  // qdmr/mesh/mesh.hpp: an OBJ or glTF mesh, read when the scene is loaded

struct OutputDesc {
  int width = 1920;
  int height = 1080;
  glm::vec3 background{0.05f, 0.06f, 0.08f};  // linear RGB where no triangle covers
};

// A camera that moves: at `frame` of the animation it is at `position`, looks at `target` with this field of view.
struct CameraKeyframe {
  int frame = 0;
  glm::vec3 position{0.0f};
  glm::vec3 target{0.0f};
  float fov_y_deg = 45.0f;
};

// Between two keyframes: straight lines at constant speed, or a cubic through every keyframe whose velocity is
// continuous (Catmull-Rom tangents over the keyframes' frame spacing) and zero at the first and the last.
enum class CameraInterpolation { Linear, Smooth };

struct CameraDesc {
  glm::vec3 position{0.0f, -3.0f, 2.0f};
  glm::vec3 target{0.0f, 0.0f, 0.0f};
  glm::vec3 up{0.0f, 0.0f, 1.0f};
  float fov_y_deg = 45.0f;  // vertical field of view
  float near = 0.05f;
  float far = 1000.0f;
  // Sorted by frame, each frame once. Non-empty: position, target and fov_y_deg are those of the frame
  // (camera_at_frame; frame 0's after loading), held before the first keyframe and after the last.
  std::vector<CameraKeyframe> keyframes;
  CameraInterpolation interpolation = CameraInterpolation::Linear;
};

// The camera at `frame`: position, target and field of view interpolated between its keyframes (in double,
// rounded once to float: the same bits whoever asks). A camera without keyframes is returned as it is.
CameraDesc camera_at_frame(const CameraDesc& camera, int frame);

struct DirectionalLightDesc {
  glm::vec3 direction{0.3f, -0.4f, 0.87f};  // towards the light; normalised by the loader
  glm::vec3 color{1.0f, 1.0f, 1.0f};
  float intensity = 1.0f;
};

struct AmbientLightDesc {
  glm::vec3 color{1.0f, 1.0f, 1.0f};
  float intensity = 0.2f;
};

struct LightsDesc {
  std::vector<DirectionalLightDesc> directional;  // up to limits::kMaxDirectionalLights
  AmbientLightDesc ambient;
};

// A procedural pattern generated at load time; deterministic for (pattern, size, seed, parameters).
enum class ProceduralPattern { Bricks, Cobbles, Sine, Steps, Spikes, Noise, Flat, Checker, Waves };

// One directional wave of the `waves` pattern: crest-sharpened sine travelling along `direction_deg` (a
// height-field stand-in for a Gerstner wave). Its wave vector is snapped to whole cycles per texture repeat, so
// the pattern tiles: `cycles` is what the loader made of wavelength and direction.
struct WaveDesc {
  float amplitude = 1.0f;      // relative: the pattern divides the sum by the amplitudes' total
  float wavelength = 0.25f;    // UV units of one repeat, before snapping
  float direction_deg = 0.0f;  // travel direction in the UV plane, 0 = +u
  float speed = 0.1f;          // UV units per second along the direction (phase speed)
  int sharpness = 1;           // crest shape ((1 + sin) / 2)^sharpness, 1 .. 8
  int cycles_u = 4, cycles_v = 0;  // the snapped wave vector, whole cycles per repeat
};

struct ProceduralDesc {
  ProceduralPattern pattern = ProceduralPattern::Noise;
  int size = 512;            // power of two, 1 .. 16384
  std::uint32_t seed = 1;
  int cells = 8;             // bricks per row / stones / sine periods / steps / spikes per side; noise base frequency
  int octaves = 5;           // noise only
  float gain = 0.5f;         // noise only: amplitude ratio between octaves
  float mortar = 0.08f;      // bricks and cobbles: gap width as a fraction of a cell
  std::vector<WaveDesc> waves;  // waves only
  glm::vec2 scroll{0.0f, 0.0f};  // UV repeats per second the pattern moves by (any pattern)
  // Seconds: the pattern is evaluated at this time (scene_at_frame sets it). Part of the content only when the
  // pattern changes with time (time_dependent).
  double time = 0.0;
};

// Whether the pattern changes with ProceduralDesc::time: a scroll, or a wave with a speed.
bool time_dependent(const ProceduralDesc& procedural);

// What the pattern's texels depend on, floats printed exactly (hexfloat): equal keys, equal patterns. The time
// and scroll are in it only where the pattern moves (time_dependent), so a still pattern keeps its key.
std::string procedural_key(const ProceduralDesc& procedural);

// Heights from a frame-numbered sequence of files (`"file": "h_%04d.exr"`, printf-style %d or %0Nd): frame n of
// the animation reads file number first + n * step. The loader checks that every frame's file exists and that
// they all have one size.
struct FileSequence {
  std::string pattern;  // absolute; empty: one file for every frame
  int first = 0;
  int step = 1;
  std::string field;    // the scene file and the field that named it (for messages)
};

// Frame `frame`'s file of a sequence.
std::filesystem::path sequence_file(const FileSequence& sequence, int frame);

// Pixels: heights handed over by a program (Renderer::update_height), not read from the scene file.
enum class TextureSource { None, File, Procedural, Constant, FromHeight, Pixels };

struct Image;  // qdmr/texture/image.hpp
enum class Channel { Default, R, G, B, A, RGB, RGBA };

// One texture slot. For albedo: colour from a file (sRGB decoded unless srgb=false), a constant,
// or a procedural pattern coloured between color_low and color_high. For normals: a file, or
// "from_height" (derived from the layer's height by central differences). For heights: one channel.
enum class TextureFormatChoice { Auto, R8, RG8, RGBA8, R16, R32F };
enum class Compression { None, Bc3 };

struct TextureDesc {
  TextureSource source = TextureSource::None;
  // Storage format. Auto: colour and normals RGBA8; heights R8 from 8-bit files, R16 from 16-bit files and
  // procedural patterns, R32F from float files.
  TextureFormatChoice format = TextureFormatChoice::Auto;
  Compression compression = Compression::None;  // heights only: BC3/DXT5 alpha blocks (implies R8)
  std::filesystem::path file;        // absolute after loading (resolved against the scene file)
  FileSequence sequence;             // heights only: `file` is then the frame's file (frame 0's after loading)
  Channel channel = Channel::Default;
  bool srgb = true;                  // albedo files only
  glm::vec3 factor{1.0f, 1.0f, 1.0f}; // albedo files only: multiplies the linear colour (glTF's baseColorFactor)
  ProceduralDesc procedural;
  glm::vec4 constant{1.0f, 1.0f, 1.0f, 1.0f};
  glm::vec3 color_low{0.25f, 0.22f, 0.2f};   // procedural albedo: colour at height 0
  glm::vec3 color_high{0.75f, 0.7f, 0.65f};  // procedural albedo: colour at height 1
  float variation = 0.15f;                    // procedural albedo: per-cell brightness jitter
  // Pixels: one channel of heights and a number naming this version of them (content keys use it, not the
  // pixels): two updates never share a number.
  std::shared_ptr<const Image> pixels;
  std::uint64_t pixels_version = 0;
};

// Whether the texture's content changes from frame to frame (a time-dependent procedural, a file sequence).
bool time_dependent(const TextureDesc& texture);

enum class NormalConvention { GL, DX };  // DX: green channel points down (-Y)

struct LayerDesc {
  TextureDesc albedo;            // default: constant white
  TextureDesc normal;            // default: from_height when a height exists, else flat
  NormalConvention normal_convention = NormalConvention::GL;
  float normal_strength = 1.0f;  // scales tangent-space xy (and slopes for from_height)
  TextureDesc height;            // default: none (flat)
  float height_scale = 1.0f;     // h' = h * height_scale + height_offset
  float height_offset = 0.0f;
  SpecularFromAlbedo specular;
  // Occlusion, roughness and metalness per texel (glTF's packing, linear): R multiplies the ambient light by
  // 1 + occlusion_strength (R - 1), G the lighting's roughness, B `metallic`. `occlusion`, when set, gives R
  // instead (one channel of an image of the orm's size). Either makes the program sample them (ProgramKey::orm);
  // single-layer materials only.
  TextureDesc orm;                 // default: none
  TextureDesc occlusion;           // default: none (R from orm, or 1)
  float metallic = 1.0f;           // metalness = B * metallic: diffuse * (1 - m), F0 lerped towards the albedo's luminance
  float occlusion_strength = 1.0f;
  bool has_orm() const { return orm.source != TextureSource::None || occlusion.source != TextureSource::None; }
};

// The intersection technique and its speed/accuracy knobs. Depth is in UV units of one texture repeat:
// the surface lies between depth 0 (the polygon) and depth_scale.
struct TechniqueDesc {
  TechniqueKind kind = TechniqueKind::Normal;
  float depth_scale = 0.05f;
  bool write_depth = false;       // displaced depth into the depth buffer
  // Take every hit from the exact fp64 reference (on the surface the technique sees) instead of tracing: the
  // reference image of this configuration, at the reference's cost. The error AOVs are then ~0.
  bool exact_hits = false;
  // relief: linear search then binary search
  int linear_steps = 32;
  int binary_steps = 6;
  // pom: step count lerped by view angle, linear intersection of the last two samples, LOD fade
  int min_steps = 8;
  int max_steps = 48;
  float lod_threshold = 4.0f;     // mip LOD where POM starts fading to normal mapping
  float lod_fade = 1.0f;          // LOD range of the fade
  // csm, rcsm and qdm: iteration cap
  int max_iterations = 128;
  // qdm
  QdmLevelUp level_up = QdmLevelUp::One;
  QdmRefinement refinement = QdmRefinement::Linear;
  HeightFetch height_fetch = HeightFetch::Bilinear;
  bool lod_stop = false;          // stop descending at the level given by the pixel's mip LOD
  int min_iterations = 0;         // > 0: the cap grows linearly from this (view along the normal) to max_iterations (grazing)
  float fade_start = 0.0f;        // > 0: depth scale fades linearly to 0 between these view distances
  float fade_end = 0.0f;
};

struct LightingDesc {
  LightingModel model = LightingModel::BlinnPhong;
  float specular = 0.25f;    // specular reflectance scale (Blinn-Phong), F0 at normal incidence (Cook-Torrance)
  float shininess = 32.0f;   // Blinn-Phong exponent
  float roughness = 0.5f;    // Cook-Torrance: GGX roughness (alpha = roughness^2)
};

struct ShadowDesc {
  ShadowMode mode = ShadowMode::Off;
  float strength = 8.0f;          // horizon, qdm_soft: occluding height (in depth-scale units) for full shadow is 1/strength
  int max_iterations = 64;        // hard: traversal cap towards the light (a capped trace counts as lit)
  int samples = 16;               // horizon: samples along the light direction; with `length` caps the shadow length
  float length = 0.0f;            // horizon, qdm_soft: longest shadow in UV units; 0 = until the light ray leaves the relief
  ProfileOperator profile = ProfileOperator::Max;
  float penumbra = 1.0f;          // horizon, qdm_soft: softening growing with the blocker's distance
  std::vector<float> tap_weights{1.0f, 1.0f, 1.0f, 1.0f, 1.0f};  // qdm_soft: artist weight per tap, near to far
  float bias = 0.0f;              // the light ray starts this fraction of the depth scale above the hit (acne on
                                  // smooth slopes, where the box surface's terraces shadow each other)
};

struct AoDesc {
  AoMode mode = AoMode::Off;
  int directions = 8;       // equally spaced horizon directions, 4..16 (clamped)
  bool jitter = false;      // rotate the directions per pixel (frame) or texel (baked) by a hash of (x, y, seed)
  std::uint32_t seed = 1;
  float radius = 0.05f;     // horizon search distance in UV units (below one texel: no occlusion)
  bool coarse = true;       // taps at 1, 2, 4, ... texels on max-quadtree level 0, 1, 2, ... (conservative, log2 of
                            // the fetches); false: a tap every texel on the filtered surface (at most 64 per direction)
  float strength = 1.0f;    // ao' = 1 - strength * (1 - ao); baked maps store ao and apply it when shading
  int resolution = 0;       // baked: texture width (0 = the height map's size); height keeps the aspect
  // baked, on heights that change every frame: each frame rebakes the rows j with j % K == frame % K of the
  // previous frame's map (frame 0 bakes them all), so a map holds the last K frames' rows. 1..kMaxAmortizeFrames.
  int amortize_frames = 1;
  static constexpr int kMaxAmortizeFrames = 64;
};

enum class WeightSource { Noise, Terrain, File };

struct WeightsDesc {
  WeightMode mode = WeightMode::Pixel;
  WeightSource source = WeightSource::Noise;
  float scale = 1.0f;       // the weight map spans this many texture repeats (set it to the mesh's uv_scale)
  int resolution = 256;     // pixel mode: side of the weight texture made from the map
  bool from_vertices = false;  // pixel mode: rasterize the weight texture from the meshes' vertex weights (the talk)
  // noise: one smooth noise field per layer at `cells` per side, sharpened; the strongest layer gets weight 1
  std::uint32_t seed = 1;
  int cells = 4;
  int sharpness = 4;         // noise: weights are the noise to this power before normalising
  // terrain: from a height map (the DEM the grid is displaced by): layer 0 on slopes, 1 on flat ground,
  // 2 below `low`, 3 where noise says so
  TextureDesc height;
  float low = 0.2f;         // normalised elevation below which layer 2 (sand) takes over
  float slope = 0.6f;       // slope (height units per map width, times `relief`) where layer 0 (rock) takes over
  float relief = 1.0f;      // vertical extent of the height map relative to its width, for slopes
  std::filesystem::path file;  // file: RGBA image, channel i = weight of layer i (linear, not sRGB)
};

// The max-quadtree QDM walks over a blend with per-pixel weights: `product` bounds each cell on the fly by
// max(hmax_i * wmax_i) from the layers' and the weights' max chains (the talk's "QDM1 * QDM2"); `combined` is
// precomputed: the max-quadtree of the blended box surface over the repeats the weights span (one fetch per
// step, exact per cell); `auto` takes combined when the weight span is a whole number of repeats and its tree
// has at most 2^22 texels per level, else product.
enum class BlendQuadtree { Auto, Combined, Product };

struct BlendDesc {
  BlendOperator op = BlendOperator::Height;
  float width = 0.2f;       // height_width: transition width in height units
  BlendQuadtree quadtree = BlendQuadtree::Auto;
  WeightsDesc weights;
};

struct MaterialDesc {
  std::string name;
  std::vector<LayerDesc> layers;  // 1 .. limits::kMaxLayers; more than one needs `blend`
  TechniqueDesc technique;
  SamplingDesc sampling;
  LightingDesc lighting;
  ShadowDesc shadow;
  AoDesc ao;
  BlendDesc blend;          // used when there is more than one layer
};

enum class MeshKind { Plane, Box, Sphere, Grid, Obj, Gltf };

// glTF: which scene or node of the asset to draw, by index or by name (neither given: the default scene).
struct GltfPick {
  int index = -1;    // >= 0: by index
  std::string name;  // non-empty: by name
  bool given() const { return index >= 0 || !name.empty(); }
};

struct MeshDesc {
  MeshKind kind = MeshKind::Plane;
  glm::vec2 size{2.0f, 2.0f};   // plane and grid: extent in x and y; box: edge length (x); sphere: diameter (x)
  glm::vec2 uv_scale{1.0f, 1.0f};
  int segments = 32;            // sphere: segments around the equator (rings = segments / 2)
  int resolution = 64;          // grid: quads per side
  TextureDesc height_map;       // grid: optional height map displacing vertices along +z
  float height = 0.0f;          // grid: z extent of the height map (scene units)
  std::filesystem::path file;   // obj, gltf: absolute path
  GltfPick gltf_scene;          // gltf: the scene drawn (default: the asset's default scene, else its first)
  GltfPick gltf_node;           // gltf: only this node and its children, placed by the node's own transform chain
};

struct TransformDesc {
  glm::vec3 translate{0.0f};
  glm::vec3 rotate_deg{0.0f};  // applied X, then Y, then Z
  glm::vec3 scale{1.0f};
};

struct ObjectDesc {
  std::string name;
  MeshDesc mesh;
  std::string material;  // a key of SceneDesc::materials; may be empty for obj and gltf meshes (their own materials)
  TransformDesc transform;
  // obj and gltf, filled by load_scene: the mesh as read, and for an object without `material`, the scene material
  // of each of the mesh's own (MTL or glTF) materials (MeshData::triangle_materials indexes this list).
  std::shared_ptr<const MeshData> obj_mesh;
  std::vector<std::string> mtl_materials;
};

// Time in a scene: frame n is at time n / fps seconds.
struct AnimationDesc {
  bool present = false;    // the scene has an "animation" block
  int frames = 1;          // frames 0 .. frames - 1
  double fps = 24.0;
  // csm and rcsm on a time-dependent height bake their cone map every frame (minutes at large sizes); without
  // this they are refused.
  bool rebake_cones = false;
};

struct SceneDesc {
  std::filesystem::path file;  // the scene file (for messages)
  AnimationDesc animation;
  int frame = 0;  // the frame of the animation the scene is at (scene_at_frame sets it)
  OutputDesc output;
  CameraDesc camera;
  LightsDesc lights;
  std::vector<MaterialDesc> materials;  // sorted by name (JSON objects are unordered), then those of MTL files
  std::vector<ObjectDesc> objects;      // submission order
  TextureCacheDesc texture_cache;       // the emulated texture cache (off unless asked for)

  // Whether any texture of the scene changes with time (what each frame rebuilds; a moving camera builds nothing).
  bool time_dependent() const;

  const MaterialDesc* find_material(const std::string& name) const {
    for (const auto& m : materials)
      if (m.name == name) return &m;
    return nullptr;
  }
};

// The scene at `seconds`: every time-dependent procedural evaluated then. Other textures are left as they are.
SceneDesc scene_at_time(const SceneDesc& scene, double seconds);
// The scene at frame `frame` of its animation: procedurals at time frame / fps, each file sequence's file of the
// frame, the camera at the frame (camera_at_frame). Frame 0 of a scene without animation is itself.
SceneDesc scene_at_frame(const SceneDesc& scene, int frame);

}  // namespace qdmr
