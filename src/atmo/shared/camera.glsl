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
