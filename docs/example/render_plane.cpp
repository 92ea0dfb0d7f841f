// Renders a scene file (e.g. scenes/plane.json) at 160x90 to an image: render_plane SCENE OUTPUT
#include <cstdio>

#include <qdmr/core/error.hpp>
#include <qdmr/render/render.hpp>
#include <qdmr/scene/load.hpp>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: render_plane SCENE OUTPUT\n");
    return 2;
  }
  try {
    const qdmr::SceneDesc scene = qdmr::load_scene(argv[1], {{"/output/width", "160"}, {"/output/height", "90"}});
    const qdmr::Frame frame = qdmr::render_frame(scene, {});
    qdmr::write_frame(frame, argv[2]);
    std::printf("%s: %dx%d, %llu pixels shaded\n", argv[2], frame.width, frame.height,
                static_cast<unsigned long long>(frame.stats.pixels_shaded));
  } catch (const qdmr::Error& e) {
    std::fprintf(stderr, "render_plane: %s\n", e.what());
    return 2;
  }
  return 0;
}
