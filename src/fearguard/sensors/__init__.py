"""Sensors other than the camera: ultrasonic range, QR localisation (turning readings into cues)."""
