MODULE GlueBead
  ! Dispense a bead around a part with rounded corners: straight edges with
  ! MoveL, corners with MoveC; the approach uses RelTool, the corners Offs.
  PERS tooldata tNozzle:=[TRUE,[[0,-12,156],[0.9659258,0,0.258819,0]],[1.1,[0,-5,70],[1,0,0,0],0,0,0]];
  TASK PERS wobjdata wPart:=[FALSE,TRUE,"",[[700,0,420],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];
  CONST num nR:=20;
  CONST num nLength:=2 * 80 + 40;
  CONST robtarget pCorner:=[[0,0,0],[0,0,1,0],[0,-1,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
  CONST robtarget pStart:=[[nR,0,0],[0,0,1,0],[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
  LOCAL CONST num nCos45:=0.7071068;

  PROC Bead()
    MoveJ RelTool(pStart, 0, 0, -50 \Rx:=10 \Rz:=-30), v1000, z20, tNozzle\WObj:=wPart;
    MoveL pStart, v200, fine, tNozzle\WObj:=wPart;
    SetDO doGlue, 1;
    MoveL Offs(pCorner, nLength - nR, 0, 0), v80, z1, tNozzle\WObj:=wPart;
    MoveC Offs(pCorner, nLength - nR + nR * (1 - nCos45), nR * (1 - nCos45), 0),
      Offs(pCorner, nLength, nR, 0), v80, z1, tNozzle\WObj:=wPart;
    MoveL Offs(pCorner, nLength, 100 - nR, 0), v80, z1, tNozzle\WObj:=wPart;
    MoveCDO Offs(pCorner, nLength - nR * (1 - nCos45), 100 - nR * (1 - nCos45), 0),
      Offs(pCorner, nLength - nR, 100, 0), v80, z1, tNozzle, doGlue, 0 \WObj:=wPart;
    MoveL RelTool(Offs(pCorner, nLength - nR, 100, 0), 0, 0, -30), v500, z10, tNozzle\WObj:=wPart;
  ENDPROC
ENDMODULE
