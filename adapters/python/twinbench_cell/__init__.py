"""twinbench_cell: the Python side of the twinbench cell protocol (proto/twinbench/cell/v1).

- drivers: RobotDriver and CameraDriver, the two interfaces a hardware adapter fills in.
- server: CellServer, the whole Cell service over them (sessions, heartbeat, checks, security).
- client: RemoteCell, a Python client of any cell server (this one or `twinbench serve-cell`).
- stubs: the generated protobuf / gRPC modules (generated at use time).
- png: PNG of 8-bit RGB images with the standard library.
"""
