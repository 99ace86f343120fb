"""uvms_tasks package: contact tasks and missions sent to the controller's ContactTask action."""
