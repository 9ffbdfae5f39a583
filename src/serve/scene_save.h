// Writes the viewer's edits into the scene file `nerfpt render` reads: a JSON scene's `volumes` entries and
// `render` settings, or a glTF file's volume nodes (translation/rotation/scale, extras.volume), punctual lights'
// intensity and scene extras. The file is rewritten from the text it had when the viewer loaded it, so saving
// twice gives the same file; the first save keeps that text as SCENE.bak.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "scene/scene.h"

namespace npt::serve {

struct SceneEditsToSave {
    std::vector<size_t> volumes;  // indices into scene.volumes whose placement or fill the viewer changed
    std::vector<std::pair<size_t, double>> light_scales;  // scene.lights index, intensity factor
    std::optional<int> spp, max_depth;
    // Camera-path keyframes (scene cameras, in order) and seconds between them: a glTF animation.
    std::vector<scene::Camera> keyframes;
    double seconds_per_key = 1.0;
    int width = 0, height = 0;  // the image size, for the path camera's aspect
};

// The file as loaded and how to write it back. Throws npt::Error for a file the viewer cannot save (.glb, .obj:
// the reason says what to do instead).
class SceneSaver {
  public:
    explicit SceneSaver(const std::filesystem::path& scene_file);
    // Whether saving is possible, and why not.
    bool can_save() const { return m_why_not.empty(); }
    const std::string& why_not() const { return m_why_not; }
    // The document as it will be written (for tests); `notes` gets one line per edit that could not be saved.
    nlohmann::json apply(const scene::Scene& scene, const SceneEditsToSave& edits, std::vector<std::string>* notes) const;
    // Writes apply()'s document over the scene file (atomically; SCENE.bak first, once per process). Returns
    // the notes. Throws npt::Error when it cannot write.
    std::vector<std::string> save(const scene::Scene& scene, const SceneEditsToSave& edits);
    // The camera path alone as a glTF file: a camera node animated through the keyframes (`nerfpt render FILE
    // --frames 1-N` renders it). Returns the number of frames at `fps`.
    static int write_camera_path(const std::filesystem::path& path, const std::vector<scene::Camera>& keys,
                                 double seconds_per_key, double fps, int width, int height);

  private:
    std::filesystem::path m_file;
    bool m_json = false;  // a JSON scene, else glTF
    nlohmann::json m_doc;
    std::string m_text;  // as loaded, for the backup
    std::string m_why_not;
    bool m_backed_up = false;
};

}  // namespace npt::serve
