"""The MAVLink bridge: fly aeroexec missions on ArduPilot Copter (GUIDED mode).

* `endpoint` — connection strings (`udpin:`, `udpout:`, `tcp:`, `tcpin:`, serial
  `DEVICE[,BAUD]`), loopback unless allowed;
* `transport` — UDP sockets, and byte streams (TCP, serial) through `streams`, pymavlink's
  own connection classes fitted to a flight link;
* `codec` — bytes <-> messages (per datagram, or a stream's); recordable packet dictionaries;
* `convert` — ENU <-> NED, yaw <-> heading, ArduCopter mode numbers;
* `link` — a transport, the codec, signing, counters, the recording tap;
* `telemetry` — received messages folded into `VehicleState` (non-finite ones refused);
* `vehicle` — `MavlinkVehicle`, the `Vehicle` protocol over MAVLink, link loss, failsafes;
* `sim_peer` — `MavSim`, the simulated vehicle speaking ArduCopter's protocol (`aeroexec mavsim`);
* `tlog` — reading telemetry logs (`.tlog`) through the same decoding path.
"""
