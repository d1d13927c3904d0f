"""The MAVLink tools built on the live vehicle backend (`aeroexec.vehicles.mavlink`:
link, codec, frames, `MavlinkVehicle`):

* `sim_peer` — `MavSim`, the simulated vehicle speaking ArduCopter's protocol (`aeroexec mavsim`);
* `tlog` — reading telemetry logs (`.tlog`) through the backend's decoding path.
"""
