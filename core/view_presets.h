// The named views: the SAGE paper's three distances, the sides of a patient, the facing a
// view of a volume takes, their names as the command line and the viewer spell them, and
// orbits. They make Cameras (core/camera.h); the camera's own math is there.
// Everything here is pure: safe to call from any thread.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include "core/camera.h"
#include "core/volume.h"

namespace vdiso {

// The three views of the SAGE paper (§4.1, Fig. 7), framed from the volume's world bounds, each
// from a facing (below) that says which way it looks. The default facing (defaultFacing(), for
// volumes without orientation) looks at the front of the volume: the eye lies from the look-at
// point along
//   kPresetViewDirection = normalize(0.35, 1, 0.3)
// (in front: +y is the face for our generated heads; a little to the side (+x) and above (+z)),
// with up = +z. Every view has a 30 degree vertical field of view.
// With c the centre of the bounds, r the radius of their bounding sphere, e = max - min:
//   Normal:  looks at c from the distance at which the sphere just fills the view, i.e. touches
//            the image's shorter side: every part of the volume is in view.
//   Distant: looks at c from so far that the sphere's image is 1/10 of the image height across
//            (the whole volume in view and small, as in the paper's distant view).
//   Closeup: looks at c + 0.35 w f, f the facing's front (+y by default) and w the bounds' width
//            along it (e.y by default): a point inside the volume near the face the camera sees,
//            where the surfaces are, from the distance at which the view is max(e) / 6 high at
//            that point. The eye is always outside the bounds (in front of that face).
// Clip planes are fitted to the bounds (fitClipPlanes).
enum class ViewPreset { Distant, Normal, Closeup };

// Which way a preset looks: the eye lies from the look-at point along toEye, up is up (not
// parallel to toEye), and a closeup looks at a point moved from the centre towards front.
// Made by defaultFacing(), patientFacing() or viewFacing(); a value-initialised one is no facing.
struct ViewFacing {
    glm::dvec3 toEye{0.0};  // unit
    glm::dvec3 up{0.0};     // unit
    glm::dvec3 front{0.0};  // unit
};

// The facing of volumes without orientation: kPresetViewDirection, up +z, front +y.
ViewFacing defaultFacing();

// The sides of a patient a camera can look at, in physical (LPS) space. Anterior puts the eye in
// front of the face looking posteriorly, posterior behind the head, left at the patient's left
// (+x in LPS), right at the right; all four with superior up. Superior looks down from above the
// head and inferior up from below the feet, both with anterior up (the face at the top).
enum class PatientSide { Anterior, Posterior, Left, Right, Superior, Inferior };

// The facing, in volume space, that looks at `side` of a volume with direction matrix
// `direction` (core/volume.h, not singular): toEye = normalize(D^-1 s), up = D^-1 u for the
// side's LPS direction s and up u, front = toEye. With a mirroring D (det < 0: a grid stored
// radiologically) volume space is physical space mirrored, so the picture is the physical view's
// mirror image (left and right change places; up is up).
ViewFacing patientFacing(PatientSide side, const glm::dmat3& direction);

// What `vdiso extract --view` and the viewer choose: a distance and, optionally, a side.
struct ViewChoice {
    ViewPreset distance = ViewPreset::Normal;
    double times = 1.0;  // with Normal: the eye at this multiple of the normal distance
    std::optional<PatientSide> side;
};

// The facing a view of `volume` takes: the side's (patientFacing) when one is chosen; else, for
// a volume with orientation, the anterior one (a head's face, upright), and defaultFacing() for
// one without. Throws std::invalid_argument when a side is chosen for a volume without
// orientation, saying so and what to use instead.
ViewFacing viewFacing(const std::optional<PatientSide>& side, const VolumeInfo& volume);

// `times` moves the eye along the line to the target to that multiple of the preset's distance.
Camera presetCamera(ViewPreset preset, const ViewFacing& facing, const glm::dvec3& boundsMin,
                    const glm::dvec3& boundsMax, int width, int height, double times = 1.0);
// With defaultFacing().
Camera presetCamera(ViewPreset preset, const glm::dvec3& boundsMin, const glm::dvec3& boundsMax,
                    int width, int height);

// `frames` cameras orbiting the bounds' centre about the facing's up: the preset's camera turned
// by 360 * k / frames degrees around the axis through its target along up (k = 0 is the preset
// itself). The "dynamic" case of SAGE: a moving camera over one volume.
std::vector<Camera> orbitCameras(ViewPreset preset, const ViewFacing& facing,
                                 const glm::dvec3& boundsMin, const glm::dvec3& boundsMax,
                                 int width, int height, int frames, double times = 1.0);
// With defaultFacing(): about +z.
std::vector<Camera> orbitCameras(ViewPreset preset, const glm::dvec3& boundsMin,
                                 const glm::dvec3& boundsMax, int width, int height, int frames);

// "distant", "normal", "closeup" (also "close-up"), case-insensitive; throws
// std::invalid_argument naming the accepted names otherwise.
ViewPreset parseViewPreset(const std::string& name);
const char* viewPresetName(ViewPreset preset);

// "anterior", "posterior", "left", "right", "superior", "inferior", case-insensitive; nullopt
// for anything else.
std::optional<PatientSide> parsePatientSide(const std::string& name);
const char* patientSideName(PatientSide side);

// A distance, a side (at the normal distance), or both joined by a comma in either order:
// "closeup", "anterior", "closeup,left". A distance may also be a multiple of the normal one,
// a positive number: "2.5" (times 2.5), "10,left". Throws std::invalid_argument naming every accepted name
// otherwise.
ViewChoice parseViewChoice(const std::string& text);
// "distance" or "distance,side" ("normal", "normal,anterior", "2.5,left"): what parseViewChoice
// reads back.
std::string viewChoiceName(const ViewChoice& choice);

}  // namespace vdiso
