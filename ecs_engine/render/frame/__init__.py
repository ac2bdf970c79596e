"""One frame from FrameData to a submitted command buffer: the Renderer, what each frame slot owns,
frame replay, the frame's chunk jobs, the camera's matrices as the frame uses them."""
