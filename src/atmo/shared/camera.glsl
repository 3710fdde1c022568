// Cameras: the view direction of each pixel, in the observer's local frame x = east, y = north,
// z = up. Azimuths are compass azimuths (0 = north, 90 degrees = east), elevations are measured
// from the horizontal. Pixel (x, y) has its centre at frag_coord = (x + 0.5, y + 0.5); row 0 is
// the top of the image.

vec3 GetDirectionFromAzimuthElevation(Number azimuth, Number elevation) {
  return vec3(cos(elevation) * sin(azimuth), cos(elevation) * cos(azimuth), sin(elevation));
}

CameraParameters MakeCameraParameters(int kind, int width, int height, Number horizontal_fov, Number yaw,
    Number pitch) {
  CameraParameters camera;
  camera.kind = kind;
  camera.width = width;
  camera.height = height;
  camera.horizontal_fov = horizontal_fov;
  camera.yaw = yaw;
  camera.pitch = pitch;
  camera.forward = GetDirectionFromAzimuthElevation(yaw, pitch);
  camera.right = vec3(cos(yaw), -sin(yaw), 0.0);
  camera.up = cross(camera.right, camera.forward);
  camera.tan_half_fov = tan(0.5 * horizontal_fov);
  return camera;
}

// Writes the view direction of the pixel; returns false where the camera sees nothing (outside
// the fisheye's circle).
bool GetCameraRayDirection(IN(CameraParameters) camera, IN(vec2) frag_coord, OUT(vec3) direction) {
  Number w = Number(camera.width);
  Number h = Number(camera.height);
  if (camera.kind == kCameraFisheye) {
    Number radius = 0.5 * min(w, h);
    Number dx = (frag_coord.x - 0.5 * w) / radius;
    Number dy = (0.5 * h - frag_coord.y) / radius;
    Number rho = sqrt(dx * dx + dy * dy);
    direction = vec3(0.0, 0.0, 1.0);
    if (rho > 1.0) {
      return false;
    }
    Number zenith = rho * 0.5 * kPi;
    // Seen from below, with north up, east is on the left.
    Number azimuth = camera.yaw + atan(-dx, dy);
    direction = vec3(sin(zenith) * sin(azimuth), sin(zenith) * cos(azimuth), cos(zenith));
    return true;
  }
  if (camera.kind == kCameraEquirect) {
    Number azimuth = camera.yaw + 2.0 * kPi * (frag_coord.x / w - 0.5);
    Number elevation = 0.5 * kPi - kPi * frag_coord.y / h;
    direction = GetDirectionFromAzimuthElevation(azimuth, elevation);
    return true;
  }
  Number x = (2.0 * frag_coord.x / w - 1.0) * camera.tan_half_fov;
  Number y = (1.0 - 2.0 * frag_coord.y / h) * camera.tan_half_fov * h / w;
  direction = normalize(camera.forward + x * camera.right + y * camera.up);
  return true;
}

// Azimuth of the view direction measured from the sun's, in [0, 2 pi), about the local zenith.
Number GetAzimuthFromSun(IN(vec3) view_direction, IN(vec3) sun_direction) {
  Number a = atan(view_direction.x * sun_direction.y - view_direction.y * sun_direction.x,
                  view_direction.x * sun_direction.x + view_direction.y * sun_direction.y);
  return a < 0.0 ? a + 2.0 * kPi : a;
}

// The inverse of GetCameraRayDirection: the frag_coord (pixel units, row 0 at the top) where the
// camera sees `direction` (unit). Returns false where it sees it nowhere: behind a perspective
// camera, outside the fisheye's circle. The equirect's x is in [0, width); the fisheye's and the
// perspective's may lie outside the image (the caller clips).
bool GetCameraFragCoordFromDirection(IN(CameraParameters) camera, IN(vec3) direction, OUT(vec2) frag_coord) {
  Number w = Number(camera.width);
  Number h = Number(camera.height);
  frag_coord = vec2(0.0);
  if (camera.kind == kCameraFisheye) {
    Number radius = 0.5 * min(w, h);
    Number zenith = atan(length(vec2(direction.x, direction.y)), direction.z);
    Number rho = zenith / (0.5 * kPi);
    // azimuth - yaw = atan(-dx, dy): dx = -rho sin(azimuth - yaw), dy = rho cos(azimuth - yaw).
    Number relative_azimuth = atan(direction.x, direction.y) - camera.yaw;
    frag_coord = vec2(0.5 * w - rho * sin(relative_azimuth) * radius, 0.5 * h - rho * cos(relative_azimuth) * radius);
    return rho <= 1.0;
  }
  if (camera.kind == kCameraEquirect) {
    Number turns = (atan(direction.x, direction.y) - camera.yaw) / (2.0 * kPi) + 0.5;
    turns = turns - floor(turns);
    Number elevation = atan(direction.z, length(vec2(direction.x, direction.y)));
    frag_coord = vec2(min(turns * w, w * (1.0 - 1e-12)), (0.5 * kPi - elevation) / kPi * h);
    return true;
  }
  Number depth = dot(direction, camera.forward);
  if (depth <= 0.0) {
    return false;
  }
  Number x = dot(direction, camera.right) / depth;
  Number y = dot(direction, camera.up) / depth;
  frag_coord = vec2((x / camera.tan_half_fov + 1.0) * 0.5 * w, (1.0 - y / (camera.tan_half_fov * h / w)) * 0.5 * h);
  return true;
}

// dOmega / dA: the solid angle per unit image area (sr per square pixel) at frag_coord; 0 where
// the camera sees nothing.
//   equirect: azimuth 2 pi x / w and elevation pi / 2 - pi y / h, dOmega = cos(elevation) dazimuth
//     delevation, so 2 pi^2 cos(elevation) / (w h);
//   fisheye (equidistant): zenith z = (pi / 2) rho, rho = (distance from the centre) / R, and
//     dA = rho R^2 drho dphi against dOmega = sin(z) dz dphi, so (pi / (2 R))^2 sin(z) / z;
//   perspective: the image plane at distance 1 has X = (2 x / w - 1) tan(fov / 2) and
//     Y = (1 - 2 y / h) tan(fov / 2) h / w, dX = dY = (2 tan(fov / 2) / w) per pixel, and
//     dOmega = dX dY / (1 + X^2 + Y^2)^(3/2).
Number GetCameraSolidAngleDensity(IN(CameraParameters) camera, IN(vec2) frag_coord) {
  Number w = Number(camera.width);
  Number h = Number(camera.height);
  if (camera.kind == kCameraFisheye) {
    Number radius = 0.5 * min(w, h);
    Number rho = length(vec2(frag_coord.x - 0.5 * w, 0.5 * h - frag_coord.y)) / radius;
    if (rho > 1.0) {
      return 0.0;
    }
    Number zenith = rho * 0.5 * kPi;
    Number scale = 0.5 * kPi / radius;
    return scale * scale * (zenith > 1e-8 ? sin(zenith) / zenith : 1.0);
  }
  if (camera.kind == kCameraEquirect) {
    Number elevation = 0.5 * kPi - kPi * frag_coord.y / h;
    return 2.0 * kPi * kPi * cos(elevation) / (w * h);
  }
  Number x = (2.0 * frag_coord.x / w - 1.0) * camera.tan_half_fov;
  Number y = (1.0 - 2.0 * frag_coord.y / h) * camera.tan_half_fov * h / w;
  Number step = 2.0 * camera.tan_half_fov / w;
  Number q = 1.0 + x * x + y * y;
  return step * step / (q * sqrt(q));
}

// The solid angle of the image-plane rectangle [0, X] x [0, Y] of a pinhole camera (the plane at
// distance 1): atan(X Y / sqrt(1 + X^2 + Y^2)), the classic closed form.
Number GetPerspectiveRectangleSolidAngle(Number x, Number y) {
  return atan(x * y / sqrt(1.0 + x * x + y * y));
}

// The solid angle of pixel (x, y), integrated exactly over its area (the part inside the fisheye's
// circle): over a whole image they sum to 4 pi (equirect) and to 2 pi (the fisheye's hemisphere).
//   equirect: (2 pi / w) (sin(elevation_top) - sin(elevation_bottom))
//             = (2 pi / w) 2 cos(elevation_centre) sin(pi / (2 h)), without cancellation;
//   perspective: inclusion-exclusion of the rectangle form above over the pixel's corners (in
//     double; float loses the difference of O(1) values for small pixels);
//   fisheye: the density above integrated by the midpoint rule on an n x n grid (n = 8 inside
//     the circle, where it is smooth; n = 64 on the rim, where the grid also finds the part
//     inside): the sum over the circle is 2 pi to < 1e-6 (tests/sun_disc_test.cc).
Number GetCameraPixelSolidAngle(IN(CameraParameters) camera, IN(ivec2) pixel) {
  Number w = Number(camera.width);
  Number h = Number(camera.height);
  if (camera.kind == kCameraEquirect) {
    Number elevation = 0.5 * kPi - kPi * (Number(pixel.y) + 0.5) / h;
    return 2.0 * kPi / w * 2.0 * cos(elevation) * sin(0.5 * kPi / h);
  }
  if (camera.kind == kCameraPerspective) {
    Number step = 2.0 * camera.tan_half_fov / w;
    Number x0 = Number(pixel.x) * step - camera.tan_half_fov;
    Number x1 = x0 + step;
    Number y1 = camera.tan_half_fov * h / w - Number(pixel.y) * step;  // the pixel's top edge
    Number y0 = y1 - step;
    return GetPerspectiveRectangleSolidAngle(x1, y1) - GetPerspectiveRectangleSolidAngle(x0, y1) -
        GetPerspectiveRectangleSolidAngle(x1, y0) + GetPerspectiveRectangleSolidAngle(x0, y0);
  }
  Number radius = 0.5 * min(w, h);
  // The corner farthest from the centre decides whether the whole pixel is inside.
  Number far_x = max(abs(Number(pixel.x) - 0.5 * w), abs(Number(pixel.x) + 1.0 - 0.5 * w));
  Number far_y = max(abs(Number(pixel.y) - 0.5 * h), abs(Number(pixel.y) + 1.0 - 0.5 * h));
  int n = far_x * far_x + far_y * far_y <= radius * radius ? 8 : 64;
  Number sum = 0.0;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      sum += GetCameraSolidAngleDensity(camera,
          vec2(Number(pixel.x) + (Number(i) + 0.5) / Number(n), Number(pixel.y) + (Number(j) + 0.5) / Number(n)));
    }
  }
  return sum / Number(n * n);
}
