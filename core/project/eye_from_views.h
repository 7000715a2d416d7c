// The eyeballs' texture from the head's own photos (issue 37: a head from
// photos with no click): where no eye photo is given, the iris is found in
// the most frontal of the photos the head was made from, at the place the
// recovered camera projects the fitted head's eyeball, and synthesized into
// the eyeball texture as an eye close-up would be (tarini2002 Sec. 4.1,
// iris/iris.h). So the person's eye colour shows instead of the generic
// brown iris.
//
// Why the eyeball's centre is the guess: a person looks into the camera in
// a frontal photo, so the iris centre lies on the line from the eyeball's
// centre to the camera and projects onto the same pixel.
#pragma once
#include "calib/camera.h"
#include "common/status.h"
#include "head/head_model.h"
#include "iris/iris.h"
#include "mesh/tri_mesh.h"
#include "project/project.h"

#include <string>
#include <vector>

namespace lk {

struct EyeFromViewsOptions {
  // An eye is tried only in a photo whose camera lies within this angle of
  // the eye's forward direction (head frame +z): farther round, the iris is
  // an ellipse and the iris circle does not fit it.
  double max_view_angle_deg = 25;
  // Smallest iris radius in pixels worth synthesizing from (the iris search
  // itself stops at 6 px).
  double min_iris_radius_px = 10;
  // How many (photo, eye) candidates are tried, most frontal first.
  int max_attempts = 4;
  // The iris's angular radius on the eyeball (EyeballTextureOptions::
  // iris_angle_deg) is measured in the photo (iris radius against the
  // eyeball's), kept within this range (adult eyes: about 27-35 deg).
  double min_iris_angle_deg = 25, max_iris_angle_deg = 40;
  // Only this photo (an index into the views) is searched, both its eyes
  // (the user marked it as the eye's photo); -1: every photo.
  int only_photo = -1;
};

struct EyeFromViewsResult {
  Image texture;          // the eyeball texture (eyeball_texture's layout)
  int photo = -1;         // index into the views it came from
  int eye = -1;           // 0 = the head's left eye (+x), 1 = its right
  IrisCircle circle;      // in that photo's pixels
  double view_angle_deg = 0;  // between the camera and the eye's forward direction
  double iris_angle_deg = 0;  // the texture's iris angular radius
  std::vector<std::string> tried;  // why each earlier candidate was not used
};

// control: the fitted control mesh (head frame, the generic head's
// topology); frame: head -> the cameras' frame; images and cameras #P (the
// photos the head was made from, their recovered cameras); names #P or
// empty ("photo 1", ...), for the messages. Fails with
// NotAHead (the message says why each candidate failed) when no photo shows
// an eye frontally and large enough, or the iris search fails in all of
// them; the caller then keeps the generic iris.
Status eye_texture_from_views(const TriMesh& control, const GenericHead& generic, const HeadFrame& frame,
                              const std::vector<const Image*>& images, const std::vector<Camera>& cameras,
                              const std::vector<std::string>& names, const EyeFromViewsOptions& options,
                              EyeFromViewsResult& out);

// The same on a head project (its fitted control mesh and frame): on
// success project.parts holds the iris and the name of the photo it came from.
Status find_project_iris(HeadProject& project, const GenericHead& generic, const std::vector<const Image*>& images,
                         const std::vector<Camera>& cameras, const std::vector<std::string>& names,
                         EyeFromViewsResult& out, const EyeFromViewsOptions& options = {});

// The index of the photo called name in names (as given, or its file name
// without folder or extension matching: "0007" finds "0007.jpg"); -1: none.
int find_photo_name(const std::vector<std::string>& names, const std::string& name);

}  // namespace lk
