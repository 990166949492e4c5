"""Your segmentation network inside segmentation_relay.py, the place to plug it in.

    rosrun evidential_octomap segmentation_relay.py cloud_in:=/os_cloud_node/points \
        _model:=$(pwd)/relay_model_template.py:OnnxEvidenceModel _model_file:=/path/net.onnx \
        _classes:=/path/my_classes.yaml

The relay builds the class once as CLASS(class_names, get_param) and calls it on every cloud with
`points`: field name -> numpy array of N values (x, y, z, intensity, ring, ... as the driver
publishes them). It must return N x C evidence (float32, >= 0), C = len(class_names), in the
order of the class table. Evidence is what an evidential (EDL) head outputs (alpha - 1); for an
ordinary softmax network, exp(logits) or a scaled softmax is a reasonable evidence.
"""
import numpy as np


def softplus(x):
    return np.logaddexp(0.0, x)


class OnnxEvidenceModel:
    """A network exported to ONNX (torch.onnx.export), run with onnxruntime on the CPU."""

    def __init__(self, class_names, get_param):
        import onnxruntime  # pip install onnxruntime; imported here so the relay starts without it
        self.num_classes = len(class_names)
        self.session = onnxruntime.InferenceSession(get_param("~model_file"),
                                                    providers=["CPUExecutionProvider"])
        self.input_name = self.session.get_inputs()[0].name

    def __call__(self, points):
        # The network's input: here N x 4 (x, y, z, intensity); change to what yours was trained on.
        features = np.stack([points["x"], points["y"], points["z"],
                             points.get("intensity", np.zeros_like(points["x"]))], axis=1)
        logits = self.session.run(None, {self.input_name: features.astype(np.float32)})[0]
        return softplus(logits).astype(np.float32)  # EDL head: evidence = softplus(logits)


class TorchEvidenceModel:
    """The same with PyTorch (torch.jit.load of a scripted model); evidence = exp(logits)."""

    def __init__(self, class_names, get_param):
        import torch
        self.torch = torch
        self.net = torch.jit.load(get_param("~model_file"), map_location="cpu").eval()

    def __call__(self, points):
        features = np.stack([points["x"], points["y"], points["z"],
                             points.get("intensity", np.zeros_like(points["x"]))], axis=1)
        with self.torch.no_grad():
            logits = self.net(self.torch.from_numpy(features.astype(np.float32))).numpy()
        return np.exp(np.clip(logits, -20, 20)).astype(np.float32)
