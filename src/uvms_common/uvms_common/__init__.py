"""What every UVMS node process shares: loopback-only DDS defaults and the node main loop."""
