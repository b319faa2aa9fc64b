"""Vision: per-frame measurements from camera pixels (lanes, exposure, occlusion, lead vehicle, QR)."""
