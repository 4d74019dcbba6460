class BridgeClient: pass
class BridgeError(Exception): pass
