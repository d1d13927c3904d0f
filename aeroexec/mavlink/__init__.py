"""The MAVLink bridge: fly aeroexec missions on ArduPilot Copter (GUIDED mode).

* `endpoint` — connection strings (`udpin:`/`udpout:`), loopback unless allowed;
* `codec` — bytes <-> messages, one datagram at a time; recordable packet dictionaries;
* `convert` — ENU <-> NED, yaw <-> heading, ArduCopter mode numbers;
* `link` — a UDP link: socket, codec, signing, counters, the recording tap;
* `telemetry` — received messages folded into `VehicleState`;
* `vehicle` — `MavlinkVehicle`, the `Vehicle` protocol over MAVLink;
* `sim_peer` — `MavSim`, the simulated vehicle speaking ArduCopter's protocol (`aeroexec mavsim`);
* `tlog` — reading telemetry logs (`.tlog`) through the same decoding path.
"""
