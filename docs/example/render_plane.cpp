// Renders a scene file (e.g. scenes/plane.json) at 160x90 from three camera positions with one Renderer, which
// prepares the scene's textures once and only draws for the second and third views; writes the last frame.
//   render_plane SCENE OUTPUT
#include <cstdio>

#include <qdmr/core/error.hpp>
#include <qdmr/load/load.hpp>
#include <qdmr/render/render.hpp>
#include <qdmr/write/write.hpp>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: render_plane SCENE OUTPUT\n");
    return 2;
  }
  try {
    qdmr::SceneDesc scene = qdmr::load_scene(argv[1], {{"/output/width", "160"}, {"/output/height", "90"}});
    qdmr::Renderer renderer;  // every core, the best ISA of this CPU
    for (int view = 0; view < 3; ++view) {
      scene.camera.position.x = -1.0f + float(view);  // a new camera touches no asset: nothing is re-prepared
      renderer.set_scene(scene);
      const qdmr::Frame& frame = renderer.draw();
      std::printf("view %d: %llu pixels shaded in %.2f ms (%s), %llu items built, %llu re-used\n", view,
                  static_cast<unsigned long long>(frame.stats.pixels_shaded), frame.stats.draw_ms(),
                  frame.stats.simd_arch.c_str(), static_cast<unsigned long long>(frame.stats.items_built),
                  static_cast<unsigned long long>(frame.stats.items_reused));
      if (view > 0 && frame.stats.items_built != 0) {
        std::fprintf(stderr, "render_plane: a camera change re-prepared assets\n");
        return 1;
      }
    }
    qdmr::write_frame(renderer.frame(), argv[2]);
    std::printf("%s: %dx%d\n", argv[2], renderer.frame().width, renderer.frame().height);
  } catch (const qdmr::Error& e) {
    std::fprintf(stderr, "render_plane: %s\n", e.what());
    return 2;
  }
  return 0;
}
